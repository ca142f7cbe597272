#include "stream_worker.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "reprise/net/fragment.hpp"
#include "reprise/server/builtin_scenes.hpp"

namespace reprise::server::detail {

namespace {

constexpr int64_t kProbeIntervalUs =
    1'000'000;  // a stalled window still sends one frame this often

double ms_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

// The low-resolution colour as a frame of its own: depth and motion taken from the full G-buffer
// at each low pixel's sample position (motion in low pixels), the camera's jitter in low pixels,
// so the colour stream predicts by reprojection like any other. The colour is m.low_color's.
GBufferView make_color_frame(Session::Media& m, glm::vec2 jitter) {
    const int lw = m.low_color.width(), lh = m.low_color.height();
    const int w = m.frame.width(), h = m.frame.height();
    const glm::vec2 footprint(float(w) / float(lw), float(h) / float(lh));
    m.low.depth.resize(lw, lh);
    m.low.motion.resize(lw, lh);
    for (int v = 0; v < lh; ++v)
        for (int u = 0; u < lw; ++u) {
            const int x =
                std::clamp(int(std::floor((u + 0.5f) * footprint.x + jitter.x)), 0, w - 1);
            const int y =
                std::clamp(int(std::floor((v + 0.5f) * footprint.y + jitter.y)), 0, h - 1);
            m.low.depth(u, v) = m.frame.depth(x, y);
            m.low.motion(u, v) = m.frame.motion(x, y) / footprint;
        }
    GBufferView low = m.low.view();
    low.color = m.low_color.view();
    low.camera = m.frame.camera;
    low.camera.jitter = jitter / footprint;
    low.fps = m.frame.fps;
    return low;
}

// lowres: both codec packets of one frame in one unit (docs/protocol.md, "Low-resolution mode").
void bundle_packets(std::span<const uint8_t> geometry, std::span<const uint8_t> color,
                    std::vector<uint8_t>& out) {
    out.resize(1 + 4 + geometry.size() + 4 + color.size());
    net::Writer w(out);
    w.u8(1);
    w.u32(uint32_t(geometry.size()));
    w.bytes(geometry);
    w.u32(uint32_t(color.size()));
    w.bytes(color);
}

}  // namespace

RenderWorker::RenderWorker(WorkerLink link)
    : link_(link),
      ladder_(link.options.aa_samples, link.options.fps, link.options.mode == net::StreamMode::Full,
              link.options.ladder) {
    publish_level();
}

RenderWorker::~RenderWorker() { stop(); }

void RenderWorker::start() {
    thread_ = std::thread([this] { loop(); });
}

void RenderWorker::stop() {
    {
        std::lock_guard lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
}

Status RenderWorker::status() const {
    std::lock_guard lock(mutex_);
    return failure_;
}

bool RenderWorker::sleep_until(int64_t when_us) {
    std::unique_lock lock(mutex_);
    const int64_t wait = std::max<int64_t>(0, when_us - net::now_us());
    wake_.wait_for(lock, std::chrono::microseconds(wait), [&] { return stop_; });
    return !stop_;
}

void RenderWorker::publish_level() {
    std::lock_guard lock(link_.stats_mutex);
    StreamServerStats& st = link_.stats;
    st.adapt_level = ladder_.level();
    st.adapt_levels = ladder_.levels();
    st.aa_samples = ladder_.current().aa_samples;
    st.fps = ladder_.current().fps;
    st.frame_cost_ms = ladder_.mean_cost_ms();
    st.adapt_steps_down = std::size_t(ladder_.steps_down());
    st.adapt_steps_up = std::size_t(ladder_.steps_up());
}

void RenderWorker::loop() {
    // The renderer's GL context lives on this thread.
    if (Status s = Renderer::create(renderer_); !s.ok()) {
        {
            std::lock_guard lock(mutex_);
            failure_ = s;
        }
        failed_ = true;
        link_.waker.wake();
        return;
    }
    warm_up();
    int64_t next_tick = net::now_us();
    while (sleep_until(next_tick)) {
        const int64_t now = net::now_us();
        {
            std::lock_guard lock(link_.sessions_mutex);
            snapshot_ = link_.sessions;
        }
        double cost_ms = 0.0;
        bool rendered = false;
        for (auto& s : snapshot_) {
            const double ms = produce(*s, now);
            cost_ms += ms;
            rendered = rendered || ms > 0.0;
        }
        snapshot_.clear();  // a session that ended is freed here or by the network thread
        if (rendered && link_.options.adapt) {
            const int before = ladder_.level();
            if (ladder_.update(cost_ms, net::now_us()))
                std::fprintf(
                    stderr,
                    "[serve] frame cost %.0f ms: adaptation level %d -> %d (aa %d, %g Hz)\n",
                    ladder_.mean_cost_ms(), before, ladder_.level(), ladder_.current().aa_samples,
                    ladder_.current().fps);
            publish_level();
        }
        const int64_t period = int64_t(1e6 / ladder_.current().fps);
        next_tick += period;
        const int64_t after = net::now_us();
        if (next_tick < after) next_tick = after;  // late: the next frame at once, none queued
    }
    renderer_.reset();
}

Status RenderWorker::scene(const std::string& name, std::shared_ptr<const LoadedScene>& out) {
    std::erase_if(scenes_, [&](const auto& entry) {  // shown by no session
        return entry.second.use_count() == 1 && entry.first != link_.options.scene;
    });
    auto it = scenes_.find(name);
    if (it == scenes_.end()) {
        auto loaded = std::make_shared<LoadedScene>();
        REPRISE_TRY(load_scene(name, loaded->scene, loaded->path));
        it = scenes_.emplace(name, std::move(loaded)).first;
    }
    out = it->second;
    return {};
}

// One frame of the default scene before any client: shader compilation and the first texture
// uploads would otherwise fall on the first session's first frame (about 0.7 s on llvmpipe).
void RenderWorker::warm_up() {
    const StreamServerOptions& o = link_.options;
    std::shared_ptr<const LoadedScene> loaded;
    if (!scene(o.scene, loaded).ok()) return;  // the session reports it
    const auto t0 = std::chrono::steady_clock::now();
    Instant at = instant_on_path(loaded->path, loaded->scene, 0.0, o.width, o.height);
    Instant before = at;
    before.time -= 1.0 / o.fps;  // as a session's first frame
    Frame frame;
    Image<glm::vec4> low;
    glm::vec2 jitter(0.0f);
    const Status s = o.mode == net::StreamMode::LowRes
                         ? renderer_->render_lowres(loaded->scene, at, before,
                                                    {.width = o.width, .height = o.height},
                                                    o.lowres_factor, 0, frame, low, jitter)
                         : renderer_->render(loaded->scene, at, before,
                                             {.width = o.width,
                                              .height = o.height,
                                              .aa_samples = ladder_.current().aa_samples},
                                             frame);
    const double render_ms = ms_since(t0);
    const auto t1 = std::chrono::steady_clock::now();
    codec::Encoder encoder;
    const Status made = codec::Encoder::create(o.encoder, encoder);  // checked by create
    codec::Packet packet;
    if (s.ok() && made.ok() && encoder.send_frame(frame).ok())
        (void)encoder.receive_packet(packet);  // warm-up: the packet is not sent
    std::fprintf(stderr, "[serve] warmed up: render %.0f ms, encode %.0f ms\n", render_ms,
                 ms_since(t1));
}

double RenderWorker::produce(Session& s, int64_t now) {
    Session::Media& m = s.media;
    net::PoseMessage pose;
    bool skip = false;
    int bitrate = 0;
    bool key_frame = false;
    std::string scene;
    {
        std::lock_guard lock(s.mutex);
        Mailbox& b = s.box;
        if (b.ended || !b.started || !b.have_pose || !b.failure.empty()) return 0.0;
        pose = b.pose;
        scene = b.scene;
        std::swap(m.acked, b.acked);
        m.lost.insert(m.lost.end(), b.lost.begin(), b.lost.end());  // after any hand-over drops
        b.lost.clear();
        key_frame = b.key_frame;
        b.key_frame = false;
        bitrate = b.bitrate_kbps;
        const bool window_full =
            m.newest_encoded - b.newest_acked >= link_.options.max_in_flight_frames;
        const bool probe = now - b.last_progress_us > kProbeIntervalUs;
        skip = b.queue_bytes > link_.options.send_queue_bytes / 2 || (window_full && !probe);
        if (!skip && probe) b.last_progress_us = now;
    }
    for (uint32_t f : m.acked) {
        m.encoder.acknowledge(f);
        m.color_encoder.acknowledge(f);
    }
    for (uint32_t f : m.lost) {
        m.encoder.report_loss(f);
        m.color_encoder.report_loss(f);
    }
    m.acked.clear();
    m.lost.clear();
    if (key_frame) {
        m.encoder.request_key_frame();
        m.color_encoder.request_key_frame();
    }
    if (bitrate > 0 && bitrate != m.bitrate_kbps) {
        m.bitrate_kbps = bitrate;
        if (link_.options.mode == net::StreamMode::LowRes) {
            // Geometry (depth + motion) and colour share the target by their usual weights.
            m.encoder.set_bitrate(std::max(1, bitrate * 2 / 3));
            m.color_encoder.set_bitrate(std::max(1, bitrate / 3));
        } else {
            m.encoder.set_bitrate(bitrate);
        }
    }
    if (!m.scene) {
        const std::string name = scene.empty() ? link_.options.scene : scene;
        if (Status st = this->scene(name, m.scene); !st.ok()) {
            std::lock_guard lock(s.mutex);
            s.box.failure = "scene: " + st.message();
            link_.waker.wake();
            return 0.0;
        }
    }
    if (skip) {
        std::lock_guard lock(link_.stats_mutex);
        ++link_.stats.frames_skipped;
        return 0.0;
    }
    double render_ms = 0.0, encode_ms = 0.0;
    if (Status st = render_encode(s, pose, render_ms, encode_ms); !st.ok()) {
        std::fprintf(stderr, "[serve] session %s ended: %s\n", s.net.peer.text().c_str(),
                     st.message().c_str());
        std::lock_guard lock(s.mutex);
        s.box.failure = st.message();
        link_.waker.wake();
        return 0.0;
    }
    if (m.frames_rendered == 1)
        std::fprintf(stderr,
                     "[serve] session %s: first frame rendered in %.0f ms, encoded in %.0f ms\n",
                     s.net.peer.text().c_str(), render_ms, encode_ms);
    {
        std::lock_guard lock(link_.stats_mutex);
        ++link_.stats.frames_encoded;
        link_.stats.render_ms_total += render_ms;
        link_.stats.encode_ms_total += encode_ms;
        codec::add_stats(link_.stats.coded, m.encoder.last_frame_stats());
        if (link_.options.mode == net::StreamMode::LowRes)
            codec::add_stats(link_.stats.coded, m.color_encoder.last_frame_stats());
    }
    return std::max(render_ms + encode_ms, 1e-3);
}

Status RenderWorker::render_encode(Session& s, const net::PoseMessage& pose, double& render_ms,
                                   double& encode_ms) {
    Session::Media& m = s.media;
    const StreamServerOptions& o = link_.options;
    const RateLevel level = ladder_.current();
    const int w = o.width, h = o.height;
    const Scene& shown = m.scene->scene;
    Instant current = instant_on_path(m.scene->path, shown, pose.scene_time, w, h);
    current.view = pose.view;
    Instant previous = current;
    previous.time = current.time - 1.0 / level.fps;
    if (m.rendered_before) previous.view = m.previous.view;
    auto t0 = std::chrono::steady_clock::now();
    const bool lowres = o.mode == net::StreamMode::LowRes;
    glm::vec2 jitter(0.0f);
    if (lowres)
        REPRISE_TRY(renderer_->render_lowres(shown, current, previous, {.width = w, .height = h},
                                             o.lowres_factor, m.frames_rendered, m.frame,
                                             m.low_color, jitter));
    else
        REPRISE_TRY(renderer_->render(shown, current, previous,
                                      {.width = w, .height = h, .aa_samples = level.aa_samples},
                                      m.frame));
    if (o.render_delay_ms > 0) sleep_until(net::now_us() + int64_t(o.render_delay_ms * 1000));
    ++m.frames_rendered;
    m.frame.fps = level.fps;
    render_ms = ms_since(t0);
    m.previous = current;
    m.rendered_before = true;
    t0 = std::chrono::steady_clock::now();
    GBufferView low;
    if (lowres) {
        low = make_color_frame(m, jitter);
        // The geometry stream carries no colour: a constant that every prediction matches.
        std::fill(m.frame.color.data(), m.frame.color.data() + m.frame.color.pixel_count(),
                  glm::vec4(0.0f));
    }
    REPRISE_TRY(m.encoder.send_frame(m.frame));
    if (m.encoder.receive_packet(m.packet) != Result::Ok)
        return Status::error("encoder gave no packet");
    std::span<const uint8_t> payload = m.packet.data;
    if (lowres) {
        REPRISE_TRY(m.color_encoder.send_frame(low));
        if (m.color_encoder.receive_packet(m.color_packet) != Result::Ok)
            return Status::error("colour encoder gave no packet");
        REPRISE_ASSERT(m.color_packet.frame == m.packet.frame);
        bundle_packets(m.packet.data, m.color_packet.data, m.bundle);
        payload = m.bundle;
    }
    m.newest_encoded = m.packet.frame;
    if (payload.size() > net::kMaxPacketBytes) {
        m.encoder.report_loss(m.packet.frame);
        m.color_encoder.report_loss(m.packet.frame);
        std::lock_guard lock(link_.stats_mutex);
        ++link_.stats.frames_dropped;
    } else {
        hand_over(s, payload, pose.client_time_us);
    }
    encode_ms = ms_since(t0);
    return {};
}

void RenderWorker::hand_over(Session& s, std::span<const uint8_t> payload, int64_t pose_time_us) {
    EncodedFrame f;
    net::FecOptions fec = link_.options.fec;
    {
        std::lock_guard lock(s.mutex);
        if (!s.box.parity) fec.group = 0;
        if (!s.box.spare.empty()) {
            f = std::move(s.box.spare.back());
            s.box.spare.pop_back();
        }
    }
    f.frame = s.media.packet.frame;
    f.count = net::fragment_packet(payload, f.frame, pose_time_us, fec, f.messages);
    f.bytes = 0;
    for (std::size_t i = 0; i < f.count; ++i) f.bytes += f.messages[i].size();
    bool dropped = false;
    {
        std::lock_guard lock(s.mutex);
        if (s.box.frames.size() >= kMaxHandover) {
            // The network thread is behind: the oldest waiting frame goes, the client never
            // sees it, so the encoders must not predict from it.
            s.media.lost.push_back(s.box.frames.front().frame);
            s.box.spare.push_back(std::move(s.box.frames.front()));
            s.box.frames.pop_front();
            dropped = true;
        }
        s.box.frames.push_back(std::move(f));
    }
    link_.waker.wake();
    if (dropped || fec.group != link_.options.fec.group) {
        std::lock_guard lock(link_.stats_mutex);
        link_.stats.frames_dropped += dropped;
        link_.stats.frames_without_parity += fec.group != link_.options.fec.group;
    }
}

}  // namespace reprise::server::detail
