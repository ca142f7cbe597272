// Encoder: reference choice (previous frame, or the newest acknowledged one after a loss), key
// frames on cuts/requests/intervals, rate control, and the sections in decoding order.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <optional>
#include <set>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include "camera_fit.hpp"
#include "decoder_state.hpp"
#include "internal.hpp"
#include "reprise/core/byte_io.hpp"
#include "reprise/core/memory_limit.hpp"

namespace reprise::codec {

namespace {

constexpr std::size_t kMaxQueuedPackets = 16;

// The rigid motions of a frame's objects, fitted to its rendered depth and motion (the camera
// motion of the rendered depth decides which objects move on their own).
std::vector<ObjectMotion> frame_objects(const EncoderOptions& options, const SequenceParams& sp,
                                        const GBufferView& frame, const Camera& camera,
                                        const Picture* ref, Image<glm::vec2>& scratch) {
    if (!options.rigid_objects || sp.motion_error <= 0.0f || sp.depth == DepthMode::None ||
        frame.id.empty() || frame.depth.empty() || frame.motion.empty())
        return {};
    ensure_size(scratch, sp.width, sp.height);
    camera_motion(camera, frame.depth, camera.prev_view, camera.prev_projection, scratch.view());
    return fit_object_motions(
        camera, frame.depth, frame.id, frame.motion, scratch.view(), sp.motion_error,
        ref ? std::span<const ObjectMotion>(ref->objects) : std::span<const ObjectMotion>());
}

// A frame's view step: the client's (E and B with this projection), finer when the camera, or an
// object relative to it, travels further than B since the previous frame, so that the motion both
// sides derive from decoded depth stays within the motion bound (docs/bitstream.md, section 6).
// An object counts up to kObjectTravel times the larger of B and the camera's travel: beyond,
// the depth it would need costs more than its motion saves. (With plane blocks, version 13, fine
// depth costs less: `fast`'s ball, 12-20x the camera's travel, now pays for its depth.)
constexpr float kObjectTravel = 20.0f;
float frame_view_step(const SequenceParams& sp, const Camera& camera,
                      std::span<const ObjectMotion> objects) {
    const int w = sp.width, h = sp.height;
    const float displacement = sp.view_displacement, motion_error = sp.motion_error;
    const float client =
        view_depth_step(camera.projection, w, h, sp.view_error, sp.view_displacement);
    if (motion_error <= 0.0f) return client;
    const glm::vec3 here = glm::vec3(glm::inverse(camera.view)[3]);
    const glm::vec3 before = glm::vec3(glm::inverse(camera.prev_view)[3]);
    float travel = glm::length(here - before);
    if (!(travel < 1e6f)) travel = 0.0f;
    const float limit = kObjectTravel * std::max(displacement, travel);
    float object_travel = 0.0f;
    for (const ObjectMotion& o : objects) {
        const float t =
            glm::length(glm::vec3(o.translation[0], o.translation[1], o.translation[2]));
        if (t <= limit) object_travel = std::max(object_travel, t);
    }
    travel = std::max(travel, object_travel);
    if (!(travel > 0.0f)) return client;
    return std::min(client, view_depth_step(camera.projection, w, h, motion_error, travel));
}

// A default Camera: Blender's render passes without cameras.json, plain video.
bool carries_no_camera(const Camera& c) {
    return !has_projection(c) && c.prev_projection == glm::mat4(1.0f) && c.view == c.prev_view;
}

void append_section(std::vector<uint8_t>& payload, const std::vector<uint8_t>& section) {
    ByteWriter w(payload);
    w.varint(section.size());
    w.bytes(section);
}

}  // namespace

struct Encoder::State {
    EncoderOptions options;
    SequenceParams sp;
    bool started = false;
    Picture refs[kReferences];
    uint32_t reference_of[kReferences] = {};
    bool tainted[kReferences] = {};  // depends on a lost frame
    uint32_t next_frame = 0;
    uint32_t last_key = 0;
    std::deque<Packet> queue;
    std::set<uint32_t> acknowledged;
    bool after_loss = false;
    bool key_requested = false;
    StreamStats stats, last;
    NonfiniteRepair repair;
    int qp = 28;
    double qp_state = 28.0;
    // Reconstruction as a Frame, made on request.
    mutable Frame recon;
    mutable bool recon_ready = false;
    int newest = -1;  // slot of the newest picture
    Planes source_planes;
    Picture scratch;
    Workspace work;

    // Frames without a camera get a fitted one: poses chained from the first such frame's camera
    // space (the previous frame's view), a lens assumed until rotation lets the fit measure it.
    struct Chain {
        glm::dmat4 pose{1.0};  // the previous frame's view
        glm::mat4 lens{0.0f};  // the measured projection; 0: not yet measured
    } chain;

    int slot_of(uint32_t frame) const { return held_slot(refs, frame); }

    // The reference for the next frame, or -1 for a key frame.
    int choose_reference() {
        const uint32_t n = next_frame;
        if (!started || key_requested) return -1;
        if (options.keyint > 0 && n - last_key >= uint32_t(options.keyint)) return -1;
        if (!after_loss) {
            const int s = slot_of(n - 1);
            if (s >= 0 && !tainted[s]) return s;
        }
        return newest_acknowledged();
    }

    // The slot of the newest held, acknowledged picture that depends on no lost frame, or -1.
    int newest_acknowledged() const {
        int best = -1;
        for (int i = 0; i < kReferences; ++i)
            if (refs[i].held && !tainted[i] && acknowledged.count(refs[i].frame) &&
                (best < 0 || refs[i].frame > refs[best].frame))
                best = i;
        return best;
    }

    // The camera to code `frame` with; `next` what the next fitted frame continues from.
    Camera camera_for(const GBufferView& frame, Chain& next, StreamStats& fs) const {
        next = chain;
        if (!options.fit_cameras || !carries_no_camera(frame.camera) || frame.depth.empty() ||
            frame.motion.empty() || options.depth == DepthMode::None)
            return frame.camera;
        const int w = frame.depth.width, h = frame.depth.height;
        CameraFit fit;
        if (chain.lens[2][3] == 0.0f) {
            // The focal length shows in how rotation bends the motion: kept once a fit rotates
            // the image centre by a pixel or more.
            fit = fit_camera(frame.depth, frame.motion, assumed_projection(w, h), true);
            const double angle = std::acos(std::clamp(
                (fit.relative[0][0] + fit.relative[1][1] + fit.relative[2][2] - 1.0) / 2.0, -1.0,
                1.0));
            if (fit.ok && 2 * fit.inliers >= fit.samples &&
                angle * fit.projection[1][1] * h / 2.0 >= 1.0)
                next.lens = fit.projection;
            else
                fit = fit_camera(frame.depth, frame.motion, assumed_projection(w, h), false);
        } else {
            fit = fit_camera(frame.depth, frame.motion, chain.lens, false);
        }
        Camera c = frame.camera;
        c.projection = c.prev_projection = fit.projection;
        c.prev_view = glm::mat4(chain.pose);
        next.pose = glm::inverse(fit.relative) * chain.pose;
        c.view = glm::mat4(next.pose);
        fs.cameras_fitted = fit.ok;
        return c;
    }

    std::vector<ObjectMotion> fit_objects(const GBufferView& frame, const Camera& camera,
                                          const Picture* ref) {
        return frame_objects(options, sp, frame, camera, ref, work.base_motion);
    }
    Status encode(const GBufferView& frame, const Camera& camera, int ref_slot, int qp_now,
                  Picture& pic, std::vector<uint8_t>& payload, StreamStats& fs,
                  ColorEncodeResult& color) {
        const bool key = ref_slot < 0;
        const Picture* ref = key ? nullptr : &refs[ref_slot];
        FrameContext fc{&sp, ref, key, &work};
        fc.models = &pic.models;
        payload.clear();
        if (key) write_params(sp, payload);

        std::vector<uint8_t> depth_section, motion_section;
        std::vector<ObjectMotion> objects;
        {
            const StageTimer timer(fs.ms.objects);
            objects = fit_objects(frame, camera, ref);
            fc.objects = objects;
            if (sp.depth == DepthMode::View) {
                fc.view_step = frame_view_step(sp, camera, objects);
                fc.camera_step = frame_view_step(sp, camera, {});
                fc.ids = frame.id;
            }
        }
        encode_depth(fc, camera, frame.depth, pic.depth, depth_section, fs);
        std::vector<uint8_t> section;
        ImageView<const glm::vec2> motion;
        {
            const StageTimer timer(fs.ms.motion);
            encode_motion(fc, camera, pic.depth.view(), frame.motion, frame.id, pic.motion,
                          pic.owner, motion_section, fs);
            pic.objects = objects;
            const std::size_t object_bytes =
                encode_camera(camera, camera.time, ref, objects, section);
            fs.camera_bits += 8 * (section.size() - object_bytes);
            fs.motion_bits += 8 * object_bytes;
            fs.motion_parts.objects += 8.0 * double(object_bytes);
            fs.motion_objects = objects.size();
            append_section(payload, section);
            append_section(payload, depth_section);
            append_section(payload, motion_section);
            motion = motion_to_reference(sp, camera, pic.depth, pic.motion, ref, next_frame, work);
        }
        section.clear();
        color = encode_color(fc, source_planes, pic.depth.view(), motion, qp_now,
                             options.skip_threshold, pic.planes, section, fs);
        append_section(payload, section);
        // The key frame parameters and section lengths (the packet header is added once written).
        fs.header_bits =
            8 * payload.size() - (fs.camera_bits + fs.depth_bits + fs.motion_bits + fs.color_bits);
        pic.camera = camera;
        pic.time = camera.time;
        pic.frame = next_frame;
        pic.held = true;
        return {};
    }
};

CodedBounds coded_bounds(const EncoderOptions& options) {
    constexpr int kAnchorQp = 34;  // the middle rate point, where the bounds are as given
    const float scale = options.bounds_follow_qp && options.qp > kAnchorQp
                            ? std::exp2(float(options.qp - kAnchorQp) / 6.0f)
                            : 1.0f;
    return {.view_error_px = std::min(options.view_error_px * scale, 100.0f),
            .motion_error_px = std::min(options.motion_error_px * scale, 8.0f)};
}

Status check_encoder_options(const EncoderOptions& o) {
    auto bad = [](const std::string& what) { return Status::error("encoder option " + what); };
    if (o.qp < 0 || o.qp > 51) return bad("qp " + std::to_string(o.qp) + ": expected 0..51");
    if (o.bitrate_kbps < 0)
        return bad("bitrate_kbps " + std::to_string(o.bitrate_kbps) + ": expected 0 or more");
    if (!(o.fps > 0.0 && o.fps <= 1000.0))
        return bad("fps " + std::to_string(o.fps) + ": expected more than 0, at most 1000");
    if (o.keyint < 0) return bad("keyint " + std::to_string(o.keyint) + ": expected 0 or more");
    if (o.chroma != Chroma::C420 && o.chroma != Chroma::C444) return bad("chroma: unknown");
    if (int(o.depth) > int(DepthMode::View)) return bad("depth: unknown mode");
    if (o.depth == DepthMode::Bounded && !(o.depth_error >= 1e-7f && o.depth_error <= 0.1f))
        return bad("depth_error: a bound in 1e-7..0.1");
    if (o.depth == DepthMode::View && !(o.view_error_px >= 1e-3f && o.view_error_px <= 100.0f &&
                                        o.view_displacement > 0.0f && o.view_displacement <= 1e6f))
        return bad("view_error_px / view_displacement: 0.001..100 px and (0, 1e6]");
    if (!(o.motion_error_px == 0.0f ||
          (o.motion_error_px >= kMinMotionError && o.motion_error_px <= 8.0f)))
        return bad("motion_error_px: 0 or 0.1..8 px");
    if (o.skip_threshold < 0 || o.skip_threshold > 255)
        return bad("skip_threshold " + std::to_string(o.skip_threshold) + ": expected 0..255");
    if (o.slices < 0 || o.slices > kMaxSlices)
        return bad("slices " + std::to_string(o.slices) + ": expected 0 (automatic) .. " +
                   std::to_string(kMaxSlices));
    return {};
}

Encoder::Encoder() : state_(std::make_unique<State>()) {
    state_->qp = state_->options.qp;
    state_->qp_state = state_->qp;
}

Status Encoder::create(const EncoderOptions& options, Encoder& encoder) {
    REPRISE_TRY(check_encoder_options(options));
    Encoder made;
    made.state_->options = options;
    made.state_->qp = options.qp;
    made.state_->qp_state = options.qp;
    encoder = std::move(made);
    return {};
}
Encoder::~Encoder() = default;
void Encoder::set_bitrate(int kbps) { state_->options.bitrate_kbps = std::max(0, kbps); }
int Encoder::bitrate() const { return state_->options.bitrate_kbps; }
Encoder::Encoder(Encoder&&) noexcept = default;
Encoder& Encoder::operator=(Encoder&&) noexcept = default;

Status Encoder::send_frame(const GBufferView& given) { return send_frame(given, {}); }

Status Encoder::send_frame(const GBufferView& given, ImageView<const glm::u8vec4> display) {
    State& s = *state_;
    const bool linear = display.empty();
    const int w = linear ? given.color.width : display.width;
    const int h = linear ? given.color.height : display.height;
    REPRISE_TRY(check_image_size(w, h, "encoder input frame " + std::to_string(s.next_frame)));
    // References, predictions, residuals and the stages' scratch: the encoder's own peak RSS was
    // 113 bytes a pixel at 1920x1080 and 119 for 1920x1080 minus 960x540 (8 frames of pan, the
    // input read beforehand); the caller's frames come on top.
    REPRISE_TRY(check_image_memory(w, h, 120, "encode"));
    if (!given.depth.empty() && (given.depth.width != w || given.depth.height != h))
        return Status::error("encoder input frame " + std::to_string(s.next_frame) +
                             ": depth size differs from colour");
    if (!given.motion.empty() && (given.motion.width != w || given.motion.height != h))
        return Status::error("encoder input frame " + std::to_string(s.next_frame) +
                             ": motion size differs from colour");
    if (s.queue.size() >= kMaxQueuedPackets)
        return Status::error("encoder: " + std::to_string(s.queue.size()) +
                             " packets not taken by receive_packet");

    // The codec codes no normals: they are neither scanned nor repaired; nor linear colour when
    // the display values come instead.
    GBufferView coded = given;
    coded.normal = {};
    if (!linear) coded.color = {};
    StreamStats::Milliseconds ms;
    NonfiniteCounts nonfinite;
    State::Chain next_chain;
    StreamStats fitted;
    std::optional<StageTimer> timer(ms.input);
    const GBufferView frame = s.repair.clean(coded, nonfinite);
    const Camera camera = s.camera_for(frame, next_chain, fitted);
    timer.reset();

    SequenceParams sp;
    sp.width = w;
    sp.height = h;
    sp.chroma = s.options.chroma;
    sp.depth = s.options.depth;
    sp.depth_error = s.options.depth_error;
    const CodedBounds bounds = coded_bounds(s.options);
    sp.motion_error = bounds.motion_error_px;
    if (sp.depth == DepthMode::View) {
        sp.view_error = bounds.view_error_px;
        sp.view_displacement = s.options.view_displacement;
        // The key frame's step; later frames send their own when it differs (a zoom, a faster
        // camera or object), so that no step change needs a key frame.
        sp.view_step = s.started ? s.sp.view_step
                                 : frame_view_step(sp, camera,
                                                   frame_objects(s.options, sp, frame, camera,
                                                                 nullptr, s.work.base_motion));
    }
    sp.slices = s.options.slices > 0 ? std::min(s.options.slices, sp.mb_rows()) : default_slices(h);
    // A new frame rate (a server stepping down) needs no key frame: the sequence keeps its key
    // frame's fps, rate control takes the frame's own.
    const double fps = frame.fps > 0.0 ? frame.fps : s.options.fps;
    sp.fps = s.started ? s.sp.fps : fps;
    if (s.started && !(sp == s.sp)) {
        s.started = false;  // new parameters: a key frame
        sp.fps = fps;
    }
    s.sp = sp;

    timer.emplace(ms.convert);
    if (linear)
        planes_from_linear(frame.color, sp, s.source_planes);
    else
        planes_from_display(display, sp, s.source_planes);
    timer.reset();
    // A cut the frame's camera reports starts a key frame; one it does not say is detected below.
    int ref = frame.camera.cut == Cut::Yes ? -1 : s.choose_reference();
    const bool detect_cut = s.options.detect_cuts && frame.camera.cut == Cut::Unknown;
    // Rate control: bounded frame sizes, re-encoding with a coarser quantiser when one is too big.
    const double target_bits =
        s.options.bitrate_kbps > 0 ? s.options.bitrate_kbps * 1000.0 / std::max(1.0, fps) : 0.0;
    int qp = s.qp;
    Picture& pic = s.scratch;
    std::vector<uint8_t> payload;
    StreamStats fs;
    for (int attempt = 0;; ++attempt) {
        fs = {.ms = fs.ms};  // a frame coded again (a cut, rate control) counts every try's time
        ColorEncodeResult color;
        const int qp_now = std::clamp(ref < 0 ? qp - 3 : qp, 0, 51);
        REPRISE_TRY(s.encode(frame, camera, ref, qp_now, pic, payload, fs, color));
        if (ref >= 0 && detect_cut && color.intra_macroblocks * 10 > color.macroblocks * 6) {
            ref = -1;  // a cut: most of the frame is new
            --attempt;
            continue;
        }
        const double bits = 8.0 * double(payload.size() + kMaxPacketHeader + 4);
        const double limit = target_bits * (ref < 0 ? 6.0 : 3.0);
        if (target_bits > 0 && bits > limit && qp < 51 && attempt < 3) {
            qp = std::min(51, qp + 6);
            continue;
        }
        break;
    }

    const bool key = ref < 0;
    PacketHeader header{key ? PacketType::Key : PacketType::Inter, s.next_frame,
                        key ? s.next_frame : s.refs[ref].frame,
                        int64_t(std::llround(camera.time * 1e6))};
    // The newest picture the receiver acknowledged stays held: after a loss the next frame
    // predicts from it even when more frames than pictures were in flight.
    const int kept = key ? -1 : s.newest_acknowledged();
    if (kept >= 0 && s.next_frame - s.refs[kept].frame <= 0xffff)
        header.kept = uint16_t(s.next_frame - s.refs[kept].frame);
    Packet packet;
    write_packet(header, payload, packet.data);
    fs.header_bits += 8 * (packet.data.size() - payload.size());
    if (target_bits > 0) {  // from the packet's size, as Encoder::resume replays it
        const double bits = 8.0 * double(packet.data.size());
        s.qp_state = std::clamp(
            s.qp_state + 0.5 * 6.0 * std::log2(std::max(bits, 1.0) / target_bits), 4.0, 51.0);
        s.qp = int(std::lround(s.qp_state));
    }
    packet.frame = header.frame;
    packet.reference = header.reference;
    packet.type = header.type;
    s.queue.push_back(std::move(packet));

    // The new picture replaces the oldest (or a free) slot, never the one kept.
    const int slot =
        replacement_slot(s.refs, header.kept ? int64_t(s.next_frame) - header.kept : -1);
    if (key) {
        for (auto& r : s.refs) r.held = false;
        s.last_key = s.next_frame;
        s.key_requested = false;
        fs.key_frames = 1;
    } else if (s.refs[ref].frame + 1 != s.next_frame) {
        fs.older_reference = 1;
    }
    s.reference_of[slot] = header.reference;
    s.tainted[slot] = !key && s.tainted[ref];
    std::swap(s.refs[slot], pic);
    // Only the newest picture's motion is read again (reconstruction()): the one before hands its
    // buffer to the next frame's picture, so two motion buffers exist instead of five.
    if (s.newest >= 0 && s.newest != slot) pic.motion = std::move(s.refs[s.newest].motion);
    s.newest = slot;
    s.after_loss = false;
    s.started = true;
    s.next_frame++;
    s.chain = next_chain;
    fs.frames = 1;
    fs.cameras_fitted = fitted.cameras_fitted;
    fs.nonfinite = nonfinite;
    fs.ms.input += ms.input;
    fs.ms.convert += ms.convert;
    s.last = fs;
    add_stats(s.stats, fs);
    s.recon_ready = false;
    return {};
}

Status Encoder::resume(std::span<const std::span<const uint8_t>> packets,
                       std::span<const double> fps) {
    State& s = *state_;
    if (s.started || s.next_frame != 0)
        return Status::error("resume: the encoder has already encoded frames");
    if (!fps.empty() && fps.size() != packets.size())
        return Status::error("resume: " + std::to_string(fps.size()) + " frame rates for " +
                             std::to_string(packets.size()) + " packets");
    Decoder decoder;
    DecodedFrame decoded;
    std::vector<uint32_t> reference_of(packets.size());
    for (uint32_t n = 0; n < packets.size(); ++n) {
        Packet info;
        int64_t timestamp = 0;
        REPRISE_TRY(inspect_packet(packets[n], info, timestamp));
        if (info.frame != n)
            return Status::error("resume: packet " + std::to_string(n) + " holds frame " +
                                 std::to_string(info.frame));
        const Status sent = decoder.send_packet(packets[n]);
        if (!sent.ok()) return Status::error("resume: " + sent.message());
        while (decoder.receive_frame(decoded) == Result::Ok) {
        }
        reference_of[n] = info.reference;
        if (info.type == PacketType::Key) s.last_key = n;
        // Rate control as send_frame ran it, from the packet's size and the frame's rate.
        const Decoder::State& d = *decoder.state_;
        const double rate = fps.empty() ? d.sp.fps : fps[n] > 0.0 ? fps[n] : s.options.fps;
        const double target_bits = s.options.bitrate_kbps > 0
                                       ? s.options.bitrate_kbps * 1000.0 / std::max(1.0, rate)
                                       : 0.0;
        if (target_bits > 0) {
            const double bits = 8.0 * double(packets[n].size());
            s.qp_state = std::clamp(
                s.qp_state + 0.5 * 6.0 * std::log2(std::max(bits, 1.0) / target_bits), 4.0, 51.0);
            s.qp = int(std::lround(s.qp_state));
        }
    }
    if (packets.empty()) return {};
    Decoder::State& d = *decoder.state_;
    s.sp = d.sp;
    decoded.release();
    for (int i = 0; i < kReferences; ++i) {
        s.refs[i] = std::move(*d.refs[i]);
        s.reference_of[i] = s.refs[i].held ? reference_of[s.refs[i].frame] : 0;
        s.tainted[i] = false;
    }
    s.next_frame = uint32_t(packets.size());
    s.newest = s.slot_of(s.next_frame - 1);
    s.started = d.started;
    if (s.newest >= 0 && has_projection(s.refs[s.newest].camera)) {
        const Camera& c = s.refs[s.newest].camera;
        s.chain.pose = glm::dmat4(c.view);
        if (c.projection != assumed_projection(s.sp.width, s.sp.height))
            s.chain.lens = c.projection;
    }
    s.stats = d.stats;
    s.recon_ready = false;
    return {};
}

Result Encoder::receive_packet(Packet& packet) {
    if (state_->queue.empty()) return Result::NeedMoreData;
    packet = std::move(state_->queue.front());
    state_->queue.pop_front();
    return Result::Ok;
}

void Encoder::flush() {}

void Encoder::acknowledge(uint32_t frame) {
    State& s = *state_;
    s.acknowledged.insert(frame);
    // Only frames still held matter.
    while (s.acknowledged.size() > 64) s.acknowledged.erase(s.acknowledged.begin());
}

void Encoder::report_loss(uint32_t frame) {
    State& s = *state_;
    if (s.started && frame < s.last_key) return;  // nothing after the newest key depends on it
    s.after_loss = true;
    // A lost frame and every held frame predicted from it (in frame order) are unusable.
    for (int pass = 0; pass < kReferences; ++pass)
        for (int i = 0; i < kReferences; ++i) {
            if (!s.refs[i].held) continue;
            if (s.refs[i].frame == frame) s.tainted[i] = true;
            const int r = s.slot_of(s.reference_of[i]);
            if (s.reference_of[i] != s.refs[i].frame &&
                (s.reference_of[i] == frame || (r >= 0 && s.tainted[r])))
                s.tainted[i] = true;
        }
}

void Encoder::request_key_frame() { state_->key_requested = true; }

const Frame& Encoder::reconstruction() const {
    const State& s = *state_;
    if (!s.recon_ready && s.newest >= 0) {
        const Picture& p = s.refs[s.newest];
        linear_from_planes(p.planes, s.sp, p.depth.view(), s.recon.color);
        s.recon.depth = p.depth;
        s.recon.motion = p.motion;
        s.recon.camera = p.camera;
        s.recon.fps = s.sp.fps;
        s.recon_ready = true;
    }
    return s.recon;
}

const StreamStats& Encoder::stats() const { return state_->stats; }
const StreamStats& Encoder::last_frame_stats() const { return state_->last; }
int Encoder::last_qp() const { return state_->qp; }

}  // namespace reprise::codec
