// reprise bench stream — the remote-rendering loop on loopback under injected faults: a server
// thread renders and encodes from the client's poses, the client extrapolates every display frame
// to its newest pose. Per condition: motion-to-photon latency, bitrate, PSNR/SSIM/FLIP of what
// was displayed against the scene rendered at the displayed poses and instants, longest freeze.
// Peers from the same run: frame repetition (the newest decoded frame shown as it is) and the
// video-only model (x264 zerolatency of the same full-resolution frames at crf 23 and 15, newest
// decoded shown), that video turned to the display pose by rotation alone (the pose-only
// timewarp of ALVR and Oculus Link), and that video plus its depth as 10-bit grey video
// extrapolated to the display pose by reprise's client warp (as immersive-video systems send it).
#include <algorithm>
#include <array>
#include <atomic>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <thread>

#include "args.hpp"
#include "bench.hpp"
#include "bench_report.hpp"
#include "codec_peers.hpp"
#include "depth_video_peer.hpp"
#include "reprise/client/stream_client.hpp"
#include "reprise/server/renderer.hpp"
#include "reprise/server/stream_server.hpp"
#include "reprise/warp/extrapolate.hpp"

namespace reprise::cli {

namespace {

struct Condition {
    std::string name;
    net::FaultOptions down, up;
};

std::vector<Condition> conditions(bool quick) {
    auto both = [](std::string name, net::FaultOptions f) {
        net::FaultOptions up = f;
        up.seed = f.seed + 1000;
        up.bandwidth_kbps = 0.0;
        return Condition{std::move(name), f, up};
    };
    std::vector<Condition> all = {
        both("clean", {}),
        both("loss1%", {.loss = 0.01, .seed = 3}),
        both("loss5%", {.loss = 0.05, .seed = 5}),
        both("burst", {.burst_start = 0.01, .burst_end = 0.15, .seed = 7}),
        both("jitter20ms", {.jitter_ms = 20.0, .reorder = 0.05, .seed = 9}),
        both("rtt50ms", {.delay_ms = 25.0, .seed = 11}),
        both("rtt100ms", {.delay_ms = 50.0, .seed = 13}),
        both("rtt100ms+loss1%", {.loss = 0.01, .delay_ms = 50.0, .jitter_ms = 5.0, .seed = 15}),
        both("cap1500kbps", {.bandwidth_kbps = 1500.0, .queue_bytes = 64 * 1024, .seed = 17}),
    };
    if (quick) return {all[0], all[2], all[6]};
    return all;
}

struct Tick {
    double t = 0.0;
    glm::mat4 view{1.0f};
    int64_t pose_us = 0, displayed_us = 0, source_pose_us = 0;
    double source_time = 0.0;
    std::size_t decoded = 0;  // frames decoded so far (a freeze keeps it)
    bool evaluated = false;
    Image<Rgb8> ours, repeated;
};

struct MethodSummary {
    std::string condition, method;
    double kbps = 0.0;
    std::vector<double> latency_ms;
    std::vector<ImageError> errors;
    double longest_freeze_ms = 0.0;
    std::size_t frames_lost = 0, fec_recovered = 0, decoded = 0;
};

double mean_of(const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return v.empty() ? NAN : s / double(v.size());
}
double percentile(std::vector<double> v, double p) {
    if (v.empty()) return NAN;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, std::size_t(p * double(v.size() - 1) + 0.5))];
}
ImageError mean_error(const std::vector<ImageError>& e) {
    ImageError m{0, 0, 0};
    for (const ImageError& x : e) {
        m.psnr += std::min(x.psnr, 60.0);
        m.ssim += x.ssim;
        m.flip += x.flip;
    }
    if (!e.empty())
        m.psnr /= double(e.size()), m.ssim /= double(e.size()), m.flip /= double(e.size());
    return m;
}

// The pose-only timewarp: every display pixel's ray turned from the display camera to the source
// camera as if it met the scene at infinity (rotation only, no depth, no translation), then
// fetched bilinearly from the decoded video frame; rays outside it take the nearest edge pixel.
void timewarp(const Image<Rgb8>& source, const glm::mat4& source_view, const glm::mat4& shown_view,
              const glm::mat4& projection, Image<Rgb8>& out) {
    const int w = source.width(), h = source.height();
    out.resize(w, h);
    const glm::mat4 unproject = glm::inverse(projection);
    const glm::mat3 turn = glm::mat3(source_view) * glm::transpose(glm::mat3(shown_view));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::vec2 ndc((x + 0.5f) / w * 2.0f - 1.0f, 1.0f - (y + 0.5f) / h * 2.0f);
            const glm::vec4 far_point = unproject * glm::vec4(ndc, 1.0f, 1.0f);
            const glm::vec3 ray = turn * (glm::vec3(far_point) / far_point.w);
            const glm::vec4 clip = projection * glm::vec4(ray, 0.0f);
            glm::vec2 p(float(w) / 2, float(h) / 2);
            if (clip.w > 1e-6f)
                p = {(clip.x / clip.w + 1.0f) * 0.5f * w, (1.0f - clip.y / clip.w) * 0.5f * h};
            const float sx = std::clamp(p.x - 0.5f, 0.0f, w - 1.0f);
            const float sy = std::clamp(p.y - 0.5f, 0.0f, h - 1.0f);
            const int x0 = int(sx), y0 = int(sy);
            const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
            const float fx = sx - x0, fy = sy - y0;
            const glm::vec3 top =
                glm::mix(glm::vec3(source(x0, y0)), glm::vec3(source(x1, y0)), fx);
            const glm::vec3 bottom =
                glm::mix(glm::vec3(source(x0, y1)), glm::vec3(source(x1, y1)), fx);
            out(x, y) = Rgb8(glm::clamp(glm::mix(top, bottom, fy) + 0.5f, 0.0f, 255.0f));
        }
}

// What a client of the colour + depth video peer holds: the decoded colour (back to linear
// light), the decoded depth and the frame's camera; no object motion is sent, so every surface
// counts as static (motion zero against a previous camera equal to its own).
void receive_peer_frame(const Image<Rgb8>& color, const Image<float>& depth, const Camera& camera,
                        Frame& out) {
    const int w = color.width(), h = color.height();
    out.color.resize(w, h);
    out.depth.resize(w, h);
    out.motion.assign(w, h, glm::vec2(0.0f));
    out.camera = camera;
    out.camera.prev_view = camera.view;
    out.camera.prev_projection = camera.projection;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Rgb8 c = color(x, y);
            const float z = depth(x, y);
            out.depth(x, y) = z;
            out.color(x, y) =
                glm::vec4(srgb_to_linear(c.r / 255.0f), srgb_to_linear(c.g / 255.0f),
                          srgb_to_linear(c.b / 255.0f), std::isfinite(z) ? 1.0f : 0.0f);
        }
}

struct StreamBench {
    const BenchOptions& options;
    int width = 256, height = 144;
    double duration = 4.0, display_rate = 120.0, fps = 30.0;
    int qp = 28;  // the server's encoder
    int aa = 1;   // the server's anti-aliasing, and the peers' source frames' (the truth has 4)
    int eval_every = 4;
    BenchScene scene;
    CsvFile csv;
    std::vector<MethodSummary> summaries;

    // The stream under condition c (lowres: reprise's lowres mode) shown at the display rate:
    // what each display tick showed, and what the server and the client counted.
    Status stream_and_display(const Condition& c, bool lowres, std::vector<Tick>& ticks,
                              server::StreamServerStats& sst, client::StreamClientStats& cst) {
        server::StreamServerOptions so{.scene = options.scene,
                                       .listen = {0x7f000001u, 0},
                                       .secret = "bench-stream",
                                       .fps = fps,
                                       .width = width,
                                       .height = height,
                                       .loopback_only = true};
        so.encoder.qp = qp;
        so.aa_samples = aa;
        if (lowres) {
            so.mode = net::StreamMode::LowRes;
            so.lowres_factor = 4;
        }
        std::unique_ptr<server::StreamServer> srv;
        REPRISE_TRY(server::StreamServer::create(so, srv));
        std::atomic<bool> stop{false};
        Status served;
        std::thread thread([&] { served = srv->run(stop); });
        client::StreamClientOptions co{.server = srv->local(),
                                       .secret = "bench-stream",
                                       .scene = options.scene,
                                       .inject_faults = true,
                                       .uplink = c.up,
                                       .downlink = c.down};
        std::unique_ptr<client::StreamClient> client;
        Status s = client::StreamClient::create(co, client);
        ticks.reserve(std::size_t(duration * display_rate) + 8);
        Image<Rgb8> rgb(width, height);
        if (s.ok())
            s = client::run_client(
                *client, duration, display_rate,
                [&](double t) { return server::camera_view(scene.path, scene.scene, t); },
                [&](const GBufferView& f, const client::DisplayInfo& info, int64_t displayed_us) {
                    Tick k;
                    k.t = info.scene_time;
                    k.view = f.camera.view;
                    k.pose_us = info.pose_us;
                    k.displayed_us = displayed_us;
                    k.source_pose_us = info.source_pose_us;
                    k.source_time = info.source_scene_time;
                    k.decoded = client->stats().frames_decoded;
                    k.evaluated = ticks.size() % eval_every == 0 && f.width() == width &&
                                  f.height() == height;
                    if (k.evaluated) {
                        k.ours = Image<Rgb8>(width, height);
                        visualize_color(f.color, k.ours.view());
                        k.repeated = Image<Rgb8>(width, height);
                        visualize_color(client->newest_decoded()->color.view(), k.repeated.view());
                    }
                    ticks.push_back(std::move(k));
                    return true;
                });
        stop = true;
        thread.join();
        REPRISE_TRY(s);
        REPRISE_TRY(served);
        sst = srv->stats();
        cst = client->stats();
        std::fprintf(stderr,
                     "[bench stream] %s: server sent %zu frames, skipped %zu; client decoded %zu, "
                     "%zu decode errors, %zu key requests\n",
                     c.name.c_str(), sst.frames_sent, sst.frames_skipped, cst.frames_decoded,
                     cst.decode_errors, cst.key_frame_requests);
        const codec::StreamStats& coded = sst.coded;
        std::fprintf(stderr,
                     "[bench stream] %s: coded %zu frames (%zu key, %zu from an older reference), "
                     "kbit: header %.1f, camera %.1f, depth %.1f, motion %.1f, colour %.1f; "
                     "sent %.1f kbit in %zu datagrams, %zu frames without parity\n",
                     c.name.c_str(), coded.frames, coded.key_frames, coded.older_reference,
                     coded.header_bits / 1e3, coded.camera_bits / 1e3, coded.depth_bits / 1e3,
                     coded.motion_bits / 1e3, coded.color_bits / 1e3, sst.bytes_sent * 8 / 1e3,
                     sst.datagrams_sent, sst.frames_without_parity);
        return {};
    }

    // Latency: ours uses the newest pose for every display frame; the peers show a frame first
    // when it arrives, so theirs is the age of its pose at that moment. Returns the longest time
    // (s) no new frame was decoded.
    static double latencies(const std::vector<Tick>& ticks, MethodSummary& ours,
                            MethodSummary& repeat) {
        std::map<int64_t, bool> first_shown;
        double freeze_start = ticks.front().t, longest = 0.0;
        std::size_t last_decoded = ticks.front().decoded;
        for (const Tick& k : ticks) {
            ours.latency_ms.push_back((k.displayed_us - k.pose_us) / 1000.0);
            if (!first_shown[k.source_pose_us]) {
                first_shown[k.source_pose_us] = true;
                repeat.latency_ms.push_back((k.displayed_us - k.source_pose_us) / 1000.0);
            }
            if (k.decoded != last_decoded) {
                longest = std::max(longest, k.t - freeze_start);
                freeze_start = k.t;
                last_decoded = k.decoded;
            }
        }
        return std::max(longest, ticks.back().t - freeze_start);
    }

    // The instants the stream's shown frames were rendered for, each once, in order.
    static std::vector<double> source_times_of(const std::vector<Tick>& ticks) {
        std::vector<double> source_times;
        for (const Tick& k : ticks)
            if (source_times.empty() || source_times.back() != k.source_time)
                source_times.push_back(k.source_time);
        std::sort(source_times.begin(), source_times.end());
        source_times.erase(std::unique(source_times.begin(), source_times.end()),
                           source_times.end());
        return source_times;
    }

    // lowres: reprise's lowres mode only (the peers come from the full-mode run).
    Status run_condition(const Condition& c, bool lowres) {
        std::vector<Tick> ticks;
        server::StreamServerStats sst;
        client::StreamClientStats cst;
        REPRISE_TRY(stream_and_display(c, lowres, ticks, sst, cst));
        if (ticks.empty())
            return Status::error("bench stream: " + c.name + ": nothing was displayed");
        const double seconds = duration;

        MethodSummary ours{c.name, lowres ? "reprise-lowres4" : "reprise",
                           sst.bytes_sent * 8.0 / seconds / 1000.0};
        MethodSummary repeat{c.name, "repetition", ours.kbps};
        MethodSummary video{c.name, "x264-crf23"}, video_fine{c.name, "x264-crf15"};
        MethodSummary warped{c.name, "x264-crf23+tw"}, with_depth{c.name, "x264+depth10"};
        const std::array<MethodSummary*, 6> all = {&ours,       &repeat, &video,
                                                   &video_fine, &warped, &with_depth};
        for (MethodSummary* m : all) {
            m->frames_lost = cst.frames_lost;
            m->fec_recovered = cst.fec_recovered;
            m->decoded = cst.frames_decoded;
        }
        const double longest = latencies(ticks, ours, repeat);
        for (MethodSummary* m : all) m->longest_freeze_ms = longest * 1000.0;
        video.latency_ms = video_fine.latency_ms = repeat.latency_ms;
        warped.latency_ms = with_depth.latency_ms = ours.latency_ms;  // at each display pose

        // The video-only peer: the same source frames (rendered at their poses) through x264.
        const int method_count = lowres ? 1 : int(all.size());
        const std::vector<double> source_times = source_times_of(ticks);
        Frame truth;
        std::vector<Image<Rgb8>> sources;
        std::vector<Image<float>> source_depth;
        std::vector<Camera> source_camera;
        for (double t : lowres ? std::vector<double>{} : source_times) {
            REPRISE_TRY(render_at(t, server::camera_view(scene.path, scene.scene, t), aa, truth));
            sources.emplace_back(width, height);
            visualize_color(truth.color.view(), sources.back().view());
            source_depth.push_back(truth.depth);  // a copy: truth is rendered into again
            source_camera.push_back(truth.camera);
        }
        // Two rate points: x264's usual crf 23 and a finer one near reprise's bitrate.
        std::vector<PeerFrame> x264, x264_fine;
        if (!lowres) {
            REPRISE_TRY(encode_decode_peer(
                sources, {.kind = PeerKind::X264, .preset = "veryfast", .crf = 23}, fps, x264));
            REPRISE_TRY(encode_decode_peer(
                sources, {.kind = PeerKind::X264, .preset = "veryfast", .crf = 15}, fps,
                x264_fine));
        }
        // The peer sends the frames the stream showed, over the same seconds as reprise's stream
        // (when the server adapts below `fps`, the same fewer frames).
        auto kbps = [&](const std::vector<PeerFrame>& frames) {
            std::size_t bytes = 0;
            for (const PeerFrame& p : frames) bytes += p.bytes;
            return bytes * 8.0 / seconds / 1000.0;
        };
        video.kbps = warped.kbps = kbps(x264);
        video_fine.kbps = kbps(x264_fine);
        // Depth beside the video: 1/z as 10-bit grey through x265 (crf 8 keeps every pixel of
        // bench codec's scenes within 0.25 px of reprojection for 16.4 cm of camera motion).
        DepthVideo depth_video;
        if (!lowres && peer_available(PeerKind::X265)) {
            std::vector<ImageView<const float>> depths;
            for (const Image<float>& d : source_depth) depths.push_back(d.view());
            REPRISE_TRY(code_depth_video(depths, fps,
                                         {.kind = PeerKind::X265, .preset = "veryfast", .crf = 8},
                                         10, depth_video));
            double bytes = double(depth_video.range_bytes);
            for (std::size_t b : depth_video.bytes) bytes += double(b);
            with_depth.kbps = video.kbps + bytes * 8.0 / seconds / 1000.0;
        }
        warp::PoseExtrapolator extrapolator;
        Frame received, extrapolated;
        const glm::mat4 projection =
            server::instant_on_path(scene.path, scene.scene, 0.0, width, height).projection;

        Image<glm::vec3> reference, shown;
        Image<Rgb8> truth_rgb(width, height), turned, warped_depth(width, height);
        int index = 0;
        for (const Tick& k : ticks) {
            if (!k.evaluated) continue;
            REPRISE_TRY(render_at(k.t, k.view, 4, truth));
            visualize_color(truth.color.view(), truth_rgb.view());
            from_rgb8(truth_rgb.view(), reference);
            const std::size_t si =
                std::lower_bound(source_times.begin(), source_times.end(), k.source_time) -
                source_times.begin();
            const Image<Rgb8>* video_frame = si < x264.size() ? &x264[si].decoded : nullptr;
            if (video_frame)
                timewarp(*video_frame, source_camera[si].view, k.view, projection, turned);
            const bool have_depth = video_frame && si < depth_video.decoded.size();
            if (have_depth) {
                receive_peer_frame(*video_frame, depth_video.decoded[si], source_camera[si],
                                   received);
                const float periods = float(std::clamp((k.t - source_times[si]) * fps, 0.0, 8.0));
                REPRISE_TRY(
                    extrapolator.extrapolate(received, k.view, projection, periods, extrapolated));
                visualize_color(extrapolated.color.view(), warped_depth.view());
            }
            const std::array<const Image<Rgb8>*, 6> candidates = {
                &k.ours,
                &k.repeated,
                video_frame,
                si < x264_fine.size() ? &x264_fine[si].decoded : nullptr,
                video_frame ? &turned : nullptr,
                have_depth ? &warped_depth : nullptr};
            for (int m = 0; m < method_count; ++m) {
                if (!candidates[m]) continue;
                from_rgb8(candidates[m]->view(), shown);
                const ImageError e = image_error(reference.view(), shown.view());
                all[m]->errors.push_back(e);
                csv.row({c.name, all[m]->method, std::to_string(index), strf("%.4f", e.psnr),
                         strf("%.6f", e.ssim), strf("%.6f", e.flip),
                         strf("%.3f", all[m] == &ours || all[m] == &warped || all[m] == &with_depth
                                          ? (k.displayed_us - k.pose_us) / 1000.0
                                          : (k.displayed_us - k.source_pose_us) / 1000.0)});
            }
            ++index;
        }
        for (MethodSummary* m : all) {
            if (lowres && m != &ours) continue;
            const ImageError e = mean_error(m->errors);
            std::printf("%-16s %-16s %9.0f %7.2f %7.4f %8.2f %8.2f %8.2f %9.0f %6zu %6zu\n",
                        c.name.c_str(), m->method.c_str(), m->kbps, e.psnr, e.flip,
                        mean_of(m->latency_ms), percentile(m->latency_ms, 0.95),
                        percentile(m->latency_ms, 1.0), m->longest_freeze_ms, m->frames_lost,
                        m->fec_recovered);
            std::fflush(stdout);
            summaries.push_back(*m);
        }
        return {};
    }

    Status render_at(double t, const glm::mat4& view, int samples, Frame& out) {
        server::Instant now = server::instant_on_path(scene.path, scene.scene, t, width, height);
        now.view = view;
        server::Instant before = now;
        before.time -= 1.0 / fps;
        return scene.renderer->render(scene.scene, now, before,
                                      {.width = width, .height = height, .aa_samples = samples},
                                      out);
    }
};

}  // namespace

Status bench_stream(const BenchOptions& options) {
    StreamBench b{options};
    REPRISE_TRY(parse_size(options.size, b.width, b.height));
    b.duration = options.stream_duration;
    b.display_rate = options.display_rate;
    if (!(b.duration > 0.5 && b.duration <= 600))
        return Status::error("--duration must be in (0.5, 600]");
    b.aa = options.aa;
    if (!server::aa_samples_valid(b.aa)) return Status::error("--aa must be 1, 2, 4, 8 or 16");
    const char* const qps_end = options.qps.data() + options.qps.size();
    if (auto [end, ec] = std::from_chars(options.qps.data(), qps_end, b.qp);
        ec != std::errc() || end != qps_end || b.qp < 0 || b.qp > 51)
        return Status::error("--qps: stream takes one qp in 0..51, not '" + options.qps + "'");
    const std::string out = options.out.empty() ? "out/bench-stream" : options.out;
    std::error_code ec;
    std::filesystem::create_directories(out, ec);
    if (ec) return Status::error(out + ": cannot create the folder: " + ec.message());
    REPRISE_TRY(open_bench_scene(options.scene, b.scene));
    REPRISE_TRY(
        b.csv.open(out + "/stream.csv", "condition,method,frame,psnr,ssim,flip,latency_ms"));
    std::printf(
        "[bench stream] %s %dx%d, server %g Hz at qp %d and aa %d, display %g Hz, %g s per "
        "condition, renderer %s\n",
        options.scene.c_str(), b.width, b.height, b.fps, b.qp, b.aa, b.display_rate, b.duration,
        b.scene.renderer->device().c_str());
    std::printf("%-16s %-16s %9s %7s %7s %8s %8s %8s %9s %6s %6s\n", "condition", "method", "kbps",
                "PSNR", "FLIP", "lat.mean", "lat.p95", "lat.max", "freeze.ms", "lost", "fec");
    std::vector<Condition> chosen = conditions(options.quick && options.conditions.empty());
    if (!options.conditions.empty()) {
        std::vector<Condition> named;
        for (const std::string& name : split_list(options.conditions)) {
            auto it = std::find_if(chosen.begin(), chosen.end(),
                                   [&](const Condition& c) { return c.name == name; });
            if (it == chosen.end())
                return Status::error("--conditions: unknown condition '" + name + "'");
            named.push_back(*it);
        }
        chosen = named;
    }
    for (const Condition& c : chosen) {
        REPRISE_TRY(b.run_condition(c, false));
        REPRISE_TRY(b.run_condition(c, true));
    }

    CsvFile summary;
    REPRISE_TRY(summary.open(
        out + "/stream_summary.csv",
        "condition,method,kbps,psnr,ssim,flip,latency_mean_ms,latency_p95_ms,latency_max_ms,"
        "longest_freeze_ms,frames_decoded,frames_lost,fec_recovered"));
    Report report;
    report.title = "reprise bench stream";
    report.paragraphs = {
        "Scene " + options.scene + " at " + options.size + ", server " + strf("%g", b.fps) +
            " Hz, display " + strf("%g", b.display_rate) + " Hz, " + strf("%g", b.duration) +
            " s per condition on loopback with the in-process fault injector on both directions.",
        "reprise: every display frame extrapolated from the newest decoded frame to the newest "
        "pose; "
        "reprise-lowres4: the same with colour sent at 1/4 of the pixels (jittered) and upsampled "
        "(Herzog 2010) "
        "before extrapolation (its own session). repetition: "
        "the newest decoded frame shown as it is (same stream). x264-crf23 / x264-crf15 (the "
        "video-only model): the same source frames through "
        "x264 veryfast zerolatency at crf 23 and 15, shown when our stream had them (same arrival "
        "times and losses; x264's "
        "error propagation after a loss is not modelled, which favours it). x264-crf23+tw: the "
        "crf 23 video turned to each display frame's pose by rotation alone (the pose-only "
        "timewarp of ALVR and Oculus Link: no depth, no translation). x264+depth10: the crf 23 "
        "video plus its depth as 10-bit grey video (1/z over the sequence's depth range, x265 "
        "veryfast crf 8, as immersive-video systems send it; bits of both counted), extrapolated "
        "to each display pose by reprise's client warp; no object motion is sent.",
        "Latency: pose sampled -> displayed, for reprise the pose each display frame was warped "
        "to, for the peers "
        "the pose of the frame the first time it is shown. Truth: the scene rendered at each "
        "displayed pose and instant with 4 anti-aliasing samples; the server renders with " +
            strf("%d", b.aa) +
            " (--aa) and the video peers' source frames are rendered with as many, at the "
            "instants the stream showed."};
    std::string table = strf("%-16s %-16s %9s %7s %7s %8s %8s %9s\n", "condition", "method", "kbps",
                             "PSNR", "FLIP", "lat.mean", "lat.p95", "freeze.ms");
    std::map<std::string, PlotSeries> by_method;
    std::vector<BarRow> latency_rows;
    for (const MethodSummary& m : b.summaries) {
        const ImageError e = mean_error(m.errors);
        summary.row({m.condition, m.method, strf("%.1f", m.kbps), strf("%.4f", e.psnr),
                     strf("%.6f", e.ssim), strf("%.6f", e.flip),
                     strf("%.3f", mean_of(m.latency_ms)),
                     strf("%.3f", percentile(m.latency_ms, 0.95)),
                     strf("%.3f", percentile(m.latency_ms, 1.0)), strf("%.1f", m.longest_freeze_ms),
                     std::to_string(m.decoded), std::to_string(m.frames_lost),
                     std::to_string(m.fec_recovered)});
        table += strf("%-16s %-16s %9.0f %7.2f %7.4f %8.2f %8.2f %9.0f\n", m.condition.c_str(),
                      m.method.c_str(), m.kbps, e.psnr, e.flip, mean_of(m.latency_ms),
                      percentile(m.latency_ms, 0.95), m.longest_freeze_ms);
        PlotSeries& s = by_method[m.method];
        s.name = m.method;
        s.x.push_back(m.kbps);
        s.y.push_back(e.psnr);
        latency_rows.push_back({m.condition + " " + m.method,
                                {mean_of(m.latency_ms), percentile(m.latency_ms, 0.95)}});
    }
    report.preformatted = table;
    std::vector<PlotSeries> series;
    for (auto& [name, s] : by_method) series.push_back(s);
    report.sections.push_back(
        {.title = "Displayed-frame error against bitrate (one point per condition)",
         .html = line_plot_svg(series, {.x_label = "kbps (log scale)", .y_label = "PSNR dB"})});
    report.sections.push_back({.title = "Motion-to-photon latency",
                               .html = bar_chart_svg(latency_rows, {"mean", "p95"}, "ms")});
    REPRISE_TRY(write_html_report(out + "/index.html", report));
    std::printf("[bench stream] %s/stream.csv, %s/stream_summary.csv, %s/index.html\n", out.c_str(),
                out.c_str(), out.c_str());
    return {};
}

}  // namespace reprise::cli
