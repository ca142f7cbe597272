// reprise render / reprise scenes
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "args.hpp"
#include "commands.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "reprise/stereo/alternate.hpp"
#include "reprise/stereo/rig.hpp"
#include "timing.hpp"

namespace reprise::cli {

namespace {

struct RenderJob {
    std::string scene = "pan";
    std::string camera;
    std::string size = "640x360";
    std::string out;
    int frames = 30;
    int start = 0;
    double fps = 30.0;
    bool unlit = false;
    std::string shading;  // lit | unlit | heavy; default: heavy for scenes built for it, else lit
    std::string reuse = "off";
    std::string refresh;
    double threshold = 8.0;  // adaptive: in 1/255 display steps
    double smoothing = 0.0;
    double depth_epsilon = 1024.0;
    int octaves = 8;
    int pcf_radius = 5;
    bool allow_outside_paths = false;
    double stereo = 0.0;       // IPD; > 0 renders both eyes into OUT/left and OUT/right
    double convergence = 0.0;  // > 0: off-axis rig converging there
    bool alternate = false;    // with stereo: render one eye per frame, synthesize the other
    int lowres = 0;  // 2 or 4: also colour at 1/lowres of the pixels, jittered, in OUT/lowres
    int aa = 4;      // anti-aliasing samples per pixel, 1 = off
};

struct ReuseTotals : server::ReuseStats {
    void add(const server::ReuseStats& s) {
        covered += s.covered, hits += s.hits, reused += s.reused, shaded += s.shaded;
        shading_ms += s.shading_ms, shading_cpu_ms += s.shading_cpu_ms;
    }
};

// What eye alternation rendered, made and took from the history.
struct AlternationTotals {
    double render_ms = 0.0, synthesis_ms = 0.0;
    std::size_t pixels = 0, from_history = 0, filled = 0, stretched = 0;
    void add(const stereo::StereoStats& s, double ms) {
        synthesis_ms += ms;
        pixels += s.covered + s.holes;
        from_history += s.from_history, filled += s.filled, stretched += s.stretched;
    }
    void print(int frames) const {
        const double n = std::max(frames, 1), p = std::max<double>(double(pixels), 1.0);
        std::printf(
            "alternating eyes: one eye rendered per frame (%.2f ms), the other synthesized "
            "(%.2f ms); of its pixels %.2f %% from the history, %.2f %% invented by the fill, "
            "%.2f %% stretched\n",
            render_ms / n, synthesis_ms / n, 100.0 * double(from_history) / p,
            100.0 * double(filled) / p, 100.0 * double(stretched) / p);
    }
};

Status parse_shading(const RenderJob& job, const server::Scene& scene,
                     server::RenderSettings& settings) {
    const std::string shading = !job.shading.empty()  ? job.shading
                                : job.unlit           ? "unlit"
                                : scene.heavy_shading ? "heavy"
                                                      : "lit";
    if (shading == "lit")
        settings.shading = server::Shading::Lit;
    else if (shading == "unlit")
        settings.shading = server::Shading::Unlit;
    else if (shading == "heavy")
        settings.shading = server::Shading::Heavy;
    else
        return Status::error("--shading '" + shading + "' must be lit, unlit or heavy");
    if (job.unlit && settings.shading != server::Shading::Unlit)
        return Status::error("--unlit contradicts --shading " + shading);
    server::ReuseSettings& reuse = settings.reuse;
    if (job.reuse == "off")
        reuse.mode = server::Reuse::Off;
    else if (job.reuse == "cache")
        reuse.mode = server::Reuse::Cache;
    else if (job.reuse == "adaptive")
        reuse.mode = server::Reuse::Adaptive, reuse.period = 16;
    else
        return Status::error("--reuse '" + job.reuse + "' must be off, cache or adaptive");
    if (reuse.mode != server::Reuse::Off && settings.shading != server::Shading::Heavy)
        return Status::error("--reuse " + job.reuse + " needs --shading heavy");
    if (!job.refresh.empty()) REPRISE_TRY(server::parse_refresh(job.refresh, reuse));
    if (!(job.threshold > 0.0 && job.threshold <= 255.0))
        return Status::error("--threshold must be in (0, 255] display steps");
    reuse.threshold = float(job.threshold / 255.0);
    if (!(job.smoothing >= 0.0 && job.smoothing <= 1.0))
        return Status::error("--smoothing must be in [0, 1]");
    reuse.smoothing = float(job.smoothing);
    if (!(job.depth_epsilon >= 0.0 && job.depth_epsilon <= 1e6))
        return Status::error("--depth-epsilon must be in [0, 1e6]");
    reuse.depth_epsilon = float(job.depth_epsilon);
    if (job.octaves < 1 || job.octaves > 16) return Status::error("--octaves must be in 1..16");
    if (job.pcf_radius < 0 || job.pcf_radius > 8) return Status::error("--pcf must be in 0..8");
    settings.heavy_octaves = job.octaves;
    settings.heavy_pcf_radius = job.pcf_radius;
    return {};
}

Status run_render(const RenderJob& job) {
    int width = 0, height = 0;
    REPRISE_TRY(parse_size(job.size, width, height));
    if (job.frames < 1 || job.frames > 1000000)
        return Status::error("--frames " + std::to_string(job.frames) + " must be in 1..1000000");
    if (job.start < 0) return Status::error("--start must not be negative");
    if (!(job.fps > 0 && job.fps <= 10000)) return Status::error("--fps must be in (0, 10000]");
    if (job.out.empty()) return Status::error("--out DIR is required");
    if (!(job.stereo >= 0.0 && job.stereo <= 1e6))
        return Status::error("--stereo IPD must be in [0, 1e6]");
    if (!(job.convergence >= 0.0 && job.convergence <= 1e30))
        return Status::error("--convergence must not be negative");
    const bool stereo = job.stereo > 0.0;
    if (job.lowres != 0 && job.lowres != 2 && job.lowres != 4)
        return Status::error("--lowres " + std::to_string(job.lowres) + " must be 2 or 4");
    if (job.lowres != 0 && stereo) return Status::error("--lowres and --stereo do not combine");
    if (job.alternate && !stereo) return Status::error("--alternate needs --stereo IPD");
    const std::string lowres_dir = job.out + "/lowres";
    const stereo::StereoRig rig{
        .ipd = float(job.stereo),
        .convergence = float(job.convergence),
        .rig = job.convergence > 0.0 ? stereo::Rig::OffAxis : stereo::Rig::Parallel};
    const std::string left_dir = stereo ? job.out + "/left" : job.out,
                      right_dir = job.out + "/right";

    server::Scene scene;
    server::CameraPath path;
    REPRISE_TRY(server::load_scene(job.scene, scene, path,
                                   {.allow_outside_paths = job.allow_outside_paths}));
    if (!job.camera.empty()) {
        server::CameraPath fallback = path;
        REPRISE_TRY(server::parse_camera_spec(job.camera, scene, fallback, path));
    }
    if (!server::aa_samples_valid(job.aa))
        return Status::error("--aa " + std::to_string(job.aa) + " must be 1, 2, 4, 8 or 16");
    server::RenderSettings settings{.width = width, .height = height, .aa_samples = job.aa};
    REPRISE_TRY(parse_shading(job, scene, settings));
    if (settings.reuse.mode != server::Reuse::Off && job.lowres)
        return Status::error(
            "--reuse and --lowres do not combine (the low-resolution pass would drop the cache)");
    if (settings.reuse.mode != server::Reuse::Off && stereo)
        return Status::error("--reuse works on one eye only (no --stereo)");
    std::unique_ptr<server::Renderer> renderer;
    REPRISE_TRY(server::Renderer::create(renderer));
    REPRISE_TRY(renderer->check_settings(settings, job.lowres ? job.lowres : 1));
    std::error_code ec;
    for (const std::string& dir :
         {left_dir, stereo ? right_dir : left_dir, job.lowres ? lowres_dir : left_dir}) {
        std::filesystem::create_directories(dir, ec);
        if (ec) return Status::error(dir + ": cannot create the folder: " + ec.message());
    }
    const std::string aa =
        settings.shading == server::Shading::Heavy || job.aa == 1 || job.lowres ? "no anti-aliasing"
        : renderer->msaa_supported(job.aa) ? std::to_string(job.aa) + "x MSAA"
                                           : std::to_string(job.aa) + "x supersampling";
    std::fprintf(stderr, "[render] %s, %dx%d, %d frames at %g Hz, %s, on %s\n", job.scene.c_str(),
                 width, height, job.frames, job.fps, aa.c_str(), renderer->device().c_str());
    ReuseTotals totals;
    Frame frame, low, made;
    stereo::EyeAlternation alternation;
    AlternationTotals alternated;
    auto begin = std::chrono::steady_clock::now();
    for (int i = 0; i < job.frames; ++i) {
        if (job.lowres) {
            glm::vec2 jitter(0.0f);
            REPRISE_TRY(renderer->render_frame_lowres(scene, path, job.start + i, job.fps, settings,
                                                      job.lowres, frame, low.color, jitter));
            REPRISE_TRY(write_frame(frame_path(job.out, i), frame));
            // Colour only; its camera is the full frame's with the jitter in its own pixels.
            low.camera = frame.camera;
            low.camera.jitter = jitter * glm::vec2(float(low.color.width()) / float(width),
                                                   float(low.color.height()) / float(height));
            low.fps = job.fps;
            REPRISE_TRY(write_frame(frame_path(lowres_dir, i), low));
        } else if (!stereo) {
            REPRISE_TRY(
                renderer->render_frame(scene, path, job.start + i, job.fps, settings, frame));
            // Frame 0 has no cache and pays llvmpipe's shader compilation: left out.
            if (settings.shading == server::Shading::Heavy && i > 0)
                totals.add(renderer->reuse_stats());
            REPRISE_TRY(write_frame(frame_path(job.out, i), frame));
        } else {
            // The path's camera is the rig's centre; each eye renders with its own view.
            const double t = (job.start + i) / job.fps;
            const server::Instant now = server::instant_on_path(path, scene, t, width, height);
            const server::Instant before =
                server::instant_on_path(path, scene, t - 1.0 / job.fps, width, height);
            Camera centre;
            centre.view = now.view;
            centre.projection = now.projection;
            centre.prev_view = before.view;
            centre.prev_projection = before.projection;
            const stereo::EyeCameras eyes = stereo::eye_cameras(centre, rig);
            auto eye_path = [&](stereo::Eye e) {
                return frame_path(e == stereo::Eye::Left ? left_dir : right_dir, i);
            };
            for (stereo::Eye e : {stereo::Eye::Left, stereo::Eye::Right}) {
                if (job.alternate && e != stereo::EyeAlternation::rendered_eye(i)) continue;
                server::Instant a = now, b = before;
                a.view = eyes[e].view;
                a.projection = eyes[e].projection;
                b.view = eyes[e].prev_view;
                b.projection = eyes[e].prev_projection;
                const auto started = BenchClock::now();
                REPRISE_TRY(renderer->render(scene, a, b, settings, frame));
                alternated.render_ms += ms_since(started);
                frame.fps = job.fps;
                REPRISE_TRY(write_frame(eye_path(e), frame));
                if (!job.alternate) continue;
                const auto synthesis = BenchClock::now();
                const stereo::StereoStats stats =
                    alternation.next(frame, e, eyes[stereo::other(e)], made);
                alternated.add(stats, ms_since(synthesis));
                made.fps = job.fps;
                REPRISE_TRY(write_frame(eye_path(stereo::other(e)), made));
            }
        }
        std::fprintf(stderr, "\r[render] %d/%d", i + 1, job.frames);
    }
    double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    std::fprintf(stderr, "\n[render] %.2f s (%.1f frames/s with EXR writing) -> %s\n", seconds,
                 job.frames / seconds, job.out.c_str());
    if (job.alternate) alternated.print(job.frames);
    const double frames = std::max(job.frames - 1, 1);
    if (settings.shading == server::Shading::Heavy)
        std::printf(
            "reuse %s: hit rate %.1f %%, pixels shaded %.1f %% (%.0f per frame), shading pass "
            "%.1f ms/frame (CPU %.1f ms), frames 1..\n",
            job.reuse.c_str(), 100.0 * totals.hit_rate(), 100.0 * totals.shaded_fraction(),
            double(totals.shaded) / frames, totals.shading_ms / frames,
            totals.shading_cpu_ms / frames);
    return {};
}

}  // namespace

int command_render(int argc, char** argv) {
    RenderJob job;
    Args args("render",
              "Renders a built-in scene or a glTF file to an EXR sequence: colour, depth, backward "
              "motion,\nnormals and object ids, frame i at time (start + i) / fps.");
    args.option("--scene", &job.scene,
                "built-in scene name (reprise scenes) or FILE.gltf/.glb; default pan");
    args.option("--frames", &job.frames, "number of frames (default 30)");
    args.option("--start", &job.start, "index of the first frame on the timeline (default 0)");
    args.option("--fps", &job.fps, "frame rate (default 30)");
    args.option("--size", &job.size, "WxH (default 640x360)");
    args.option("--camera", &job.camera,
                "KIND[:key=value,...], KIND static|orbit|pan|dolly|shake|cut, keys speed, radius, "
                "height,\nshake, time, angle (orbit:speed=0.5,radius=3); or gltf[:N], the file's "
                "N-th camera");
    args.flag("--unlit", &job.unlit, "base colour only (view-independent shading)");
    args.option("--shading", &job.shading,
                "lit|unlit|heavy (default: heavy for courtyard and stroll, else lit)");
    args.option("--reuse", &job.reuse,
                "off|cache|adaptive: heavy shading reuses its expensive term through a "
                "reprojection cache (default off)");
    args.option(
        "--refresh", &job.refresh,
        "KIND:N with --reuse: tiled|random|blocks|interleaved, each pixel reshaded at "
        "least every N frames (default blocks:4; adaptive: N caps the deadline, default 16)");
    args.option("--octaves", &job.octaves,
                "heavy: noise octaves per layer, three layers (default 8)");
    args.option("--pcf", &job.pcf_radius, "heavy: PCF radius r, (2r+1)^2 shadow taps (default 5)");
    args.option("--threshold", &job.threshold,
                "adaptive: allowed change per channel in 1/255 (default 8)");
    args.option("--depth-epsilon", &job.depth_epsilon,
                "cache hit test: depth tolerance in 24-bit Z-buffer steps (default 1024)");
    args.option("--smoothing", &job.smoothing,
                "amortized shadow supersampling alpha on cache hits (0 = off, default)");
    args.flag(
        "--allow-outside-paths", &job.allow_outside_paths,
        "let a glTF file read buffers and images outside its own folder (trusted files only)");
    args.option(
        "--stereo", &job.stereo,
        "IPD: render both eyes (the camera is the rig's centre) into OUT/left and OUT/right");
    args.option("--convergence", &job.convergence,
                "with --stereo: off-axis rig converging at this distance");
    args.flag("--alternate", &job.alternate,
              "with --stereo: render one eye per frame (left on even frames, right on odd) and "
              "synthesize\nthe other from it, holes filled from that eye's last rendered frame "
              "(Didyk et al. 2010)");
    args.option(
        "--lowres", &job.lowres,
        "2|4: also colour at 1/2 (W/2 x H) or 1/4 (W/2 x H/2) of the pixels with a per-frame "
        "sub-pixel jitter, in OUT/lowres (colour only; reprise:jitter in its own pixels); "
        "OUT keeps the full-resolution G-buffer (reprise upsample)");
    args.option("--aa", &job.aa,
                "anti-aliased colour: 1 (off), 2, 4, 8 or 16 samples per pixel (default 4; MSAA "
                "where the device has the count, else supersampling). Depth, motion, normals, "
                "ids stay single samples at the pixel centre; heavy shading and --lowres renders "
                "are single-sample");
    args.option("--out", &job.out, "output folder (required)");
    Status parsed = args.parse(argc, argv);
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    return report(args, parsed, run_render(job));
}

int command_scenes(int argc, char** argv) {
    Args args("scenes", "Lists the built-in scenes and what each one stresses.");
    Status parsed = args.parse(argc, argv);
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    for (const server::SceneInfo& s : server::builtin_scenes())
        std::printf("%-9s %s\n", s.name, s.stresses);
    return 0;
}

}  // namespace reprise::cli
