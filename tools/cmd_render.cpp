// reprise render / reprise scenes
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "args.hpp"
#include "commands.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"

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
};

Status run_render(const RenderJob& job) {
    int width = 0, height = 0;
    REPRISE_TRY(parse_size(job.size, width, height));
    if (job.frames < 1 || job.frames > 1000000)
        return Status::error("--frames " + std::to_string(job.frames) + " must be in 1..1000000");
    if (job.start < 0) return Status::error("--start must not be negative");
    if (!(job.fps > 0 && job.fps <= 10000))
        return Status::error("--fps must be in (0, 10000]");
    if (job.out.empty()) return Status::error("--out DIR is required");

    server::Scene scene;
    server::CameraPath path;
    REPRISE_TRY(server::load_scene(job.scene, scene, path));
    if (!job.camera.empty()) {
        server::CameraPath fallback = path;
        REPRISE_TRY(server::parse_camera_spec(job.camera, scene, fallback, path));
    }
    std::error_code ec;
    std::filesystem::create_directories(job.out, ec);
    if (ec) return Status::error(job.out + ": cannot create the folder: " + ec.message());

    std::unique_ptr<server::Renderer> renderer;
    REPRISE_TRY(server::Renderer::create(renderer));
    std::fprintf(stderr, "[render] %s, %dx%d, %d frames at %g Hz on %s\n", job.scene.c_str(),
                 width, height, job.frames, job.fps, renderer->device().c_str());
    const server::RenderSettings settings{
        .width = width,
        .height = height,
        .shading = job.unlit ? server::Shading::Unlit : server::Shading::Lit};
    Frame frame;
    auto begin = std::chrono::steady_clock::now();
    for (int i = 0; i < job.frames; ++i) {
        REPRISE_TRY(renderer->render_frame(scene, path, job.start + i, job.fps, settings, frame));
        REPRISE_TRY(write_frame(frame_path(job.out, i), frame));
        std::fprintf(stderr, "\r[render] %d/%d", i + 1, job.frames);
    }
    double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    std::fprintf(stderr, "\n[render] %.2f s (%.1f frames/s with EXR writing) -> %s\n", seconds,
                 job.frames / seconds, job.out.c_str());
    return {};
}

}  // namespace

int command_render(int argc, char** argv) {
    RenderJob job;
    Args args("render",
              "Renders a built-in scene or a glTF file to an EXR sequence: colour, depth, backward "
              "motion,\nnormals and object ids, frame i at time (start + i) / fps.");
    args.option("--scene", &job.scene, "built-in scene name (reprise scenes) or FILE.gltf/.glb; default pan");
    args.option("--frames", &job.frames, "number of frames (default 30)");
    args.option("--start", &job.start, "index of the first frame on the timeline (default 0)");
    args.option("--fps", &job.fps, "frame rate (default 30)");
    args.option("--size", &job.size, "WxH (default 640x360)");
    args.option("--camera", &job.camera,
                "static|orbit|pan|dolly|shake|cut|gltf[:N] with ,key=value (speed, radius, "
                "height, shake, time, angle)");
    args.flag("--unlit", &job.unlit, "base colour only (view-independent shading)");
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
