// reprise serve / reprise connect — the remote-rendering loop.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "args.hpp"
#include "commands.hpp"
#include "frame_writer.hpp"
#include "reprise/client/stream_client.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/gpu/fruc_backend.hpp"
#include "reprise/gpu/upsampler.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "reprise/server/stream_server.hpp"
#include "stream_window.hpp"

namespace reprise::cli {

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop.store(true); }

constexpr std::size_t kMinPinLength = 6;

// Where the PIN comes from: --pin, --pin-file (first line) or REPRISE_PIN (argv is visible to
// every user in `ps`; a file or the environment is not). Short PINs only with --allow-weak-pin.
struct PinSource {
    std::string pin, file;
    bool allow_weak = false;
};

Status resolve_pin(const PinSource& source, std::string& pin) {
    if (!source.pin.empty() && !source.file.empty())
        return Status::error("--pin and --pin-file: give one of them");
    if (!source.file.empty()) {
        std::ifstream in(source.file);
        if (!in) return Status::error("--pin-file " + source.file + ": cannot open");
        std::getline(in, pin);
        if (!pin.empty() && pin.back() == '\r') pin.pop_back();
        if (pin.empty()) return Status::error("--pin-file " + source.file + ": first line empty");
    } else if (!source.pin.empty()) {
        pin = source.pin;
    } else if (const char* env = std::getenv("REPRISE_PIN"); env && *env) {
        pin = env;
    } else {
        return Status::error("--pin, --pin-file or REPRISE_PIN is required");
    }
    if (pin.size() > 255) return Status::error("--pin: at most 255 characters");
    if (pin.size() < kMinPinLength && !source.allow_weak)
        return Status::error("--pin: " + std::to_string(pin.size()) +
                             " characters; at least 6 (or --allow-weak-pin; docs/protocol.md "
                             "gives the guessing rate)");
    return {};
}

struct ServeJob {
    std::string scene = "pan", listen = "127.0.0.1:7000", size = "640x360", mode = "full";
    PinSource pin;
    double fps = 30.0, duration = 0.0;
    bool duration_given = false, metrics_port_given = false, no_adapt = false;
    int max_sessions = 4, qp = 28, bitrate = 0, fec_group = 8, metrics_port = -1, lowres = 4,
        aa = 4;
};

Status run_serve(const ServeJob& job) {
    server::StreamServerOptions o;
    o.scene = job.scene;
    REPRISE_TRY(net::parse_endpoint(job.listen, o.listen));
    REPRISE_TRY(resolve_pin(job.pin, o.secret));
    if (job.duration_given && !(job.duration > 0.0))
        return Status::error(
            "--duration must be more than 0 seconds (leave it out to serve "
            "until SIGINT)");
    if (job.metrics_port_given && (job.metrics_port < 0 || job.metrics_port > 65535))
        return Status::error("--metrics-port must be 0..65535 (0: any free port)");
    REPRISE_TRY(parse_size(job.size, o.width, o.height));
    o.fps = job.fps;
    if (job.mode == "full")
        o.mode = net::StreamMode::Full;
    else if (job.mode == "lowres")
        o.mode = net::StreamMode::LowRes;
    else
        return Status::error("--mode must be full or lowres");
    if (job.lowres != 2 && job.lowres != 4) return Status::error("--lowres must be 2 or 4");
    o.lowres_factor = job.lowres;
    if (!server::aa_samples_valid(job.aa)) return Status::error("--aa must be 1, 2, 4, 8 or 16");
    o.aa_samples = job.aa;
    o.max_sessions = job.max_sessions;
    if (job.qp < 0 || job.qp > 51) return Status::error("--qp must be 0..51");
    o.encoder.qp = job.qp;
    if (job.bitrate < 0 || job.bitrate > 1000000)
        return Status::error("--bitrate must be 0..1000000 kbps");
    o.bitrate_kbps = job.bitrate;
    if (job.fec_group < 0 || job.fec_group > 255)
        return Status::error("--fec-group must be 0..255");
    o.fec.group = job.fec_group;
    o.metrics_port = job.metrics_port;
    o.adapt = !job.no_adapt;
    // The served scene must load before anyone connects.
    server::Scene scene;
    server::CameraPath path;
    REPRISE_TRY(server::load_scene(job.scene, scene, path));
    if (!o.listen.loopback())
        std::fprintf(stderr,
                     "[serve] warning: listening on %s, beyond loopback (127.0.0.0/8): anyone "
                     "who reaches it can guess the PIN online (docs/protocol.md, threat model)\n",
                     o.listen.text().c_str());
    std::unique_ptr<server::StreamServer> srv;
    REPRISE_TRY(server::StreamServer::create(o, srv));
    std::fprintf(stderr, "[serve] %s on %s, %dx%d at %g Hz, %s mode%s\n", job.scene.c_str(),
                 srv->local().text().c_str(), o.width, o.height, o.fps, job.mode.c_str(),
                 o.metrics_port >= 0
                     ? (", metrics on 127.0.0.1:" + std::to_string(srv->metrics_port())).c_str()
                     : "");
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::thread timer;
    if (job.duration > 0) {
        timer = std::thread([d = job.duration] {
            const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(d);
            while (!g_stop.load() && std::chrono::steady_clock::now() < end)
                std::this_thread::sleep_for(std::chrono::milliseconds(20));
            g_stop.store(true);
        });
    }
    Status s = srv->run(g_stop);
    g_stop.store(true);
    if (timer.joinable()) timer.join();
    const server::StreamServerStats st = srv->stats();
    std::fprintf(
        stderr,
        "[serve] %zu sessions, %zu frames sent, %zu skipped, %zu dropped, %.1f MB, %zu datagrams "
        "dropped, %zu refused (server full)\n",
        st.sessions_total, st.frames_sent, st.frames_skipped, st.frames_dropped,
        st.bytes_sent / 1e6, st.dropped_datagrams, st.refused_full);
    const double frames = double(std::max<std::size_t>(st.frames_encoded, 1));
    std::fprintf(stderr,
                 "[serve] mean render %.1f ms, encode %.1f ms; adaptation level %d of %d (aa %d, "
                 "%g Hz), %zu steps down, %zu up\n",
                 st.render_ms_total / frames, st.encode_ms_total / frames, st.adapt_level,
                 st.adapt_levels - 1, st.aa_samples, st.fps, st.adapt_steps_down,
                 st.adapt_steps_up);
    return s;
}

struct ConnectJob {
    std::string server, scene, camera, out, poses;
    PinSource pin;
    double display_rate = 120.0, duration = 10.0;
    bool no_extrapolate = false, window = false, interactive = false;
    double loss = 0.0, delay = 0.0, jitter = 0.0;
    std::string backend = "cpu";
};

// --poses FILE: lines "t m00 m01 ... m33" (scene time, then the world -> camera matrix column by
// column); the pose in force at t is the last line with a time <= t.
Status read_poses(const std::string& file, std::vector<std::pair<double, glm::mat4>>& poses) {
    std::ifstream in(file);
    if (!in) return Status::error(file + ": cannot open");
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
        ++number;
        if (line.empty() || line[0] == '#') continue;
        std::istringstream fields(line);
        double t;
        glm::mat4 m;
        fields >> t;
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) fields >> m[c][r];
        if (!fields || !std::isfinite(t))
            return Status::error(file + ":" + std::to_string(number) + ": expected 17 numbers");
        if (!poses.empty() && t < poses.back().first)
            return Status::error(file + ":" + std::to_string(number) + ": times must not decrease");
        if (poses.size() >= 1000000) return Status::error(file + ": more than 10^6 poses");
        poses.emplace_back(t, m);
    }
    if (poses.empty()) return Status::error(file + ": no poses");
    return {};
}

Status run_connect(const ConnectJob& job) {
    client::StreamClientOptions o;
    REPRISE_TRY(net::parse_endpoint(job.server, o.server));
    REPRISE_TRY(resolve_pin(job.pin, o.secret));
    if (!(job.duration > 0.0)) return Status::error("--duration must be more than 0 seconds");
    if (!job.scene.empty() && !net::valid_scene_name(job.scene))
        return Status::error(
            "--scene '" + job.scene +
            "': a name from the server's catalogue (1..32 of [a-z0-9_-]), never a path");
    o.scene = job.scene;
    o.extrapolate = !job.no_extrapolate;
    if (job.backend != "cpu" && job.backend != "gles")
        return Status::error("--backend '" + job.backend + "': expected cpu or gles");
    if (job.loss > 0 || job.delay > 0 || job.jitter > 0) {
        if (!(job.loss >= 0 && job.loss <= 1)) return Status::error("--loss must be in [0, 1]");
        o.inject_faults = true;
        o.downlink = {.loss = job.loss, .delay_ms = job.delay / 2, .jitter_ms = job.jitter};
        o.uplink = {
            .loss = job.loss, .delay_ms = job.delay / 2, .jitter_ms = job.jitter, .seed = 2};
    }
    // The camera: a path of a built-in scene (the client's catalogue name) or a pose file.
    std::vector<std::pair<double, glm::mat4>> poses;
    server::Scene scene;
    server::CameraPath path;
    if (!job.poses.empty()) {
        REPRISE_TRY(read_poses(job.poses, poses));
    } else {
        REPRISE_TRY(server::load_scene(job.scene.empty() ? "pan" : job.scene, scene, path));
        if (!job.camera.empty()) {
            const server::CameraPath fallback = path;
            REPRISE_TRY(server::parse_camera_spec(job.camera, scene, fallback, path));
        }
    }
    // The window before the GPU: with --backend gles the GPU works in the window's OpenGL ES
    // context (so the context outlives the GPU's objects), and the frames it extrapolates are
    // drawn from their textures; without --out nothing is downloaded. Where the window gets no
    // such context, SDL's software renderer draws downloaded frames beside the GPU's own context.
    const bool gles = job.backend == "gles";
    std::unique_ptr<StreamWindow> window;
    std::unique_ptr<gpu::Context> gpu;
    if (job.window || job.interactive) {
        const glm::mat4 start =
            poses.empty() ? server::camera_view(path, scene, 0.0) : poses.front().second;
        if (gles) {
            Status on_gl =
                StreamWindow::open(job.interactive, start, StreamWindow::Drawing::GlEs, window);
            if (on_gl.ok()) on_gl = gpu::Context::adopt_current(gpu);
            if (!on_gl.ok()) {
                gpu.reset();
                window.reset();
                std::fprintf(stderr,
                             "[connect] no OpenGL ES window (%s): SDL's software renderer draws "
                             "the downloaded frames\n",
                             on_gl.message().c_str());
            }
        }
        if (!window)
            REPRISE_TRY(StreamWindow::open(
                job.interactive, start,
                gles ? StreamWindow::Drawing::SdlSoftware : StreamWindow::Drawing::Sdl, window));
    }
    // --backend gles: each display frame extrapolated on the GPU (the CPU's method: the grid,
    // pull-push), a lowres stream's colour upsampled there and handed to the extrapolation as a
    // texture (downloaded only for a reader on the CPU).
    std::unique_ptr<gpu::FrucBackend> backend;
    std::unique_ptr<gpu::Upsampler> upsampler;
    const bool kept_on_gpu = gpu && job.out.empty();
    if (gles) {
        if (!gpu) REPRISE_TRY(gpu::Context::create(gpu));
        backend = std::make_unique<gpu::FrucBackend>(*gpu);
        backend->keep_extrapolated_on_gpu(kept_on_gpu);
        o.extrapolation.backend = backend.get();
        REPRISE_TRY(gpu::Upsampler::create(*gpu, {}, upsampler));
        o.upsampler = upsampler.get();
        if (o.extrapolate) {
            upsampler->keep_output(true);
            REPRISE_TRY(backend->inputs_from(upsampler.get()));
            o.upsampled_colour_stays = true;
        }
    }
    double last_t = 0.0;
    bool window_open = true, window_error = false;
    client::PoseFunction pose = [&](double t) {
        if (window) {
            window_open = window->pump(t - last_t) && window_open;
            last_t = t;
            if (job.interactive) return window->view();
        }
        if (poses.empty()) return server::camera_view(path, scene, t);
        auto it = std::upper_bound(
            poses.begin(), poses.end(), t,
            [](double v, const std::pair<double, glm::mat4>& p) { return v < p.first; });
        return it == poses.begin() ? poses.front().second : std::prev(it)->second;
    };
    if (!job.out.empty()) {
        std::error_code ec;
        std::filesystem::create_directories(job.out, ec);
        if (ec) return Status::error(job.out + ": cannot create the folder: " + ec.message());
    }
    std::unique_ptr<client::StreamClient> c;
    REPRISE_TRY(client::StreamClient::create(o, c));
    std::ofstream log;
    if (!job.out.empty()) {
        log.open(job.out + "/display.csv");
        log << "index,scene_time,pose_us,displayed_us,latency_ms,source_scene_time,source_latency_"
               "ms,written\n";
    }
    // EXR writing on its own thread: the display loop only copies the frame into a free slot.
    std::unique_ptr<FrameWriter> writer;
    if (!job.out.empty()) writer = std::make_unique<FrameWriter>(job.out);
    int index = 0;
    double latency_sum = 0.0;
    REPRISE_TRY(client::run_client(
        *c, job.duration, job.display_rate, pose,
        [&](const GBufferView& f, const client::DisplayInfo& info, int64_t displayed_us) {
            const double latency = (displayed_us - info.pose_us) / 1000.0;
            latency_sum += latency;
            if (writer) {
                const bool written = writer->submit(f, index, info.scene_time, job.display_rate);
                log << index << ',' << info.scene_time << ',' << info.pose_us << ',' << displayed_us
                    << ',' << latency << ',' << info.source_scene_time << ','
                    << (displayed_us - info.source_pose_us) / 1000.0 << ',' << int(written) << '\n';
            }
            // A frame the GPU extrapolated is drawn from its texture (kept there without --out).
            if (window) {
                const bool texture = backend && info.extrapolated && window->draws_textures();
                const Status shown = texture ? window->show(backend->made()) : window->show(f);
                if (!shown.ok() && !window_error) {
                    std::fprintf(stderr, "[connect] window: %s\n", shown.message().c_str());
                    window_error = true;
                }
            }
            ++index;
            return !g_stop.load() && window_open;
        }));
    if (writer) {
        REPRISE_TRY(writer->finish());
        std::fprintf(stderr,
                     "[connect] %zu frames written to %s, %zu not written (the writer fell "
                     "behind the display)\n",
                     writer->written(), job.out.c_str(), writer->dropped());
    }
    const client::StreamClientStats& st = c->stats();
    std::fprintf(
        stderr,
        "[connect] %d frames displayed, %zu decoded, %zu lost, %zu recovered by FEC, %zu connects, "
        "mean motion-to-photon %.2f ms, last round trip %.1f ms\n",
        index, st.frames_decoded, st.frames_lost, st.fec_recovered, st.connects,
        index ? latency_sum / index : 0.0, st.last_rtt_us / 1000.0);
    if (backend && backend->frames() > 0) {
        const double n = double(backend->frames());
        std::fprintf(stderr,
                     "[connect] %zu frames extrapolated on the GPU (%s; %zu from the frame "
                     "uploaded for the one before): upload %.2f, compute %.2f, download %.2f ms a "
                     "frame%s\n",
                     backend->frames(), gpu->description().c_str(), backend->uploads_kept(),
                     backend->total().upload_ms / n, backend->total().compute_ms / n,
                     backend->total().download_ms / n,
                     kept_on_gpu ? "; kept on the GPU and drawn from there by the window" : "");
    }
    if (upsampler && upsampler->frames() > 0) {
        const double n = double(upsampler->frames());
        std::fprintf(stderr,
                     "[connect] %zu frames upsampled on the GPU: upload %.2f, compute %.2f, "
                     "download %.2f ms a frame%s\n",
                     upsampler->frames(), upsampler->total().upload_ms / n,
                     upsampler->total().compute_ms / n, upsampler->total().download_ms / n,
                     o.upsampled_colour_stays
                         ? "; the colour handed to the extrapolation as a texture"
                         : "");
    }
    if (st.backend_errors > 0)
        std::fprintf(stderr,
                     "[connect] %zu frames the GPU failed on (extrapolated ones shown as decoded, "
                     "upsampled ones made on the CPU): %s\n",
                     st.backend_errors, st.backend_error.c_str());
    if (index == 0) return Status::error("no frame was decoded from " + job.server);
    return {};
}

}  // namespace

int command_serve(int argc, char** argv) {
    ServeJob job;
    Args args(
        "serve",
        "Serves a scene to streaming clients: renders from each client's pose, encodes, sends.");
    args.option("--scene", &job.scene,
                "built-in scene or glTF file served by default (default pan)");
    args.option("--listen", &job.listen, "UDP address A.B.C.D:PORT (default 127.0.0.1:7000)");
    args.option("--pin", &job.pin.pin,
                "PIN or token clients must know, at least 6 characters (never sent; visible in "
                "ps: prefer --pin-file or REPRISE_PIN)");
    args.option("--pin-file", &job.pin.file, "read the PIN from the first line of this file");
    args.flag("--allow-weak-pin", &job.pin.allow_weak,
              "accept a PIN shorter than 6 characters (guessed in hours, docs/protocol.md)");
    args.option("--fps", &job.fps, "server frame rate (default 30)");
    args.option("--size", &job.size, "WxH (default 640x360)");
    args.option("--mode", &job.mode, "full (default) or lowres");
    args.option("--lowres", &job.lowres,
                "lowres mode: 2 or 4 pixels per colour sample (default 4)");
    args.option("--aa", &job.aa,
                "anti-aliased colour, samples per pixel: 1 (off, fastest), 2, 4 (default), 8, 16");
    args.option("--max-sessions", &job.max_sessions,
                "sessions at once; more are told \"server full\" (default 4)");
    args.flag("--no-adapt", &job.no_adapt,
              "keep --aa and --fps even when frames take longer than a period");
    args.option("--qp", &job.qp, "quantiser when no --bitrate (default 28)");
    args.option("--bitrate", &job.bitrate,
                "start bitrate in kbps, adapted to loss (default 0: constant quality)");
    args.option("--fec-group", &job.fec_group,
                "data fragments per parity fragment, 0 = no FEC (default 8)");
    args.option("--metrics-port", &job.metrics_port, "Prometheus text metrics on 127.0.0.1:PORT");
    args.option("--duration", &job.duration,
                "stop after this many seconds (default: until SIGINT)");
    Status parsed = args.parse(argc, argv);
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    job.duration_given = args.given("--duration");
    job.metrics_port_given = args.given("--metrics-port");
    return report(args, parsed, run_serve(job));
}

int command_connect(int argc, char** argv) {
    ConnectJob job;
    Args args("connect",
              "Connects to `reprise serve`, shows the stream at the display rate, extrapolated to "
              "the newest pose.");
    args.positional("HOST:PORT", &job.server, "server address");
    args.option("--pin", &job.pin.pin,
                "the server's PIN or token (or --pin-file, or REPRISE_PIN in the environment)");
    args.option("--pin-file", &job.pin.file, "read the PIN from the first line of this file");
    args.flag("--allow-weak-pin", &job.pin.allow_weak, "accept a PIN shorter than 6 characters");
    args.option("--scene", &job.scene, "scene from the server's catalogue (default: the server's)");
    args.option("--display-rate", &job.display_rate, "display frames per second (default 120)");
    args.option("--camera", &job.camera,
                "camera path spec of the scene (see reprise render --help)");
    args.option("--poses", &job.poses,
                "pose file: lines 't m00 .. m33' (view matrix column by column)");
    args.option("--out", &job.out,
                "write displayed frames as EXR (camera = pose, time = display time) + display.csv");
    args.option("--duration", &job.duration, "seconds (default 10)");
    args.flag("--window", &job.window, "show the displayed frames in an SDL2 window (Esc closes)");
    args.flag("--interactive", &job.interactive,
              "window with a free camera: WASD, Q/E, arrows, mouse drag");
    args.flag("--no-extrapolate", &job.no_extrapolate, "show the newest decoded frame as it is");
    args.option("--backend", &job.backend,
                "cpu | gles (default cpu); gles: each display frame extrapolated (the grid, "
                "pull-push) and\na lowres stream's colour upsampled by OpenGL ES; "
                "with --window the GPU works in\nthe window's context and draws its frames from "
                "their textures (nothing downloaded unless --out)");
    args.option("--loss", &job.loss, "fault injector: random loss each way (0..1)");
    args.option("--delay", &job.delay, "fault injector: round-trip delay in ms");
    args.option("--jitter", &job.jitter, "fault injector: jitter in ms each way");
    Status parsed = args.parse(argc, argv);
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    return report(args, parsed, run_connect(job));
}

}  // namespace reprise::cli
