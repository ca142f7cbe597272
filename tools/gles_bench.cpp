// reprise-gles-bench: the GPU backend's stages beside their CPU references (the table of
// `reprise bench paths --backend gles`) in an executable that needs only the renderer's and the
// GPU backend's libraries, so that it can be copied to a machine with a GPU and nothing else.
#include <cstdio>
#include <string>
#include <vector>

#include "args.hpp"
#include "bench.hpp"
#include "timing.hpp"

namespace reprise::cli {
namespace {

Status run(const std::string& scene, const std::string& sizes, int frames) {
    BenchScene bench;
    REPRISE_TRY(open_bench_scene(scene, bench));
    std::printf("scene %s from frame 10, %d timed frames\n", scene.c_str(), frames);
    for (const std::string& size : split_list(sizes)) {
        int w = 0, h = 0;
        REPRISE_TRY(parse_size(size, w, h));
        std::vector<Frame> rendered(std::size_t(frames + 2));
        for (int i = 0; i < frames + 2; ++i)
            REPRISE_TRY(bench.renderer->render_frame(bench.scene, bench.path, 10 + i, 30.0,
                                                     {.width = w, .height = h},
                                                     rendered[std::size_t(i)]));
        REPRISE_TRY(bench_gles_stages(rendered, size));
    }
    return {};
}

}  // namespace
}  // namespace reprise::cli

int main(int argc, char** argv) {
    using namespace reprise::cli;
    std::string scene = "pan", sizes = "640x360,1920x1080";
    int frames = 10;
    Args args("gles-bench",
              "The GPU backend's stages beside their CPU references on rendered frames (upload, "
              "compute and download apart; the GPU result's PSNR against the CPU's).");
    args.option("--scene", &scene, "built-in scene (default pan)");
    args.option("--sizes", &sizes, "comma-separated WxH (default 640x360,1920x1080)");
    args.option("--frames", &frames, "timed frames per size (default 10)");
    const reprise::Status parsed = args.parse(argc - 1, argv + 1);
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    if (frames < 1)
        return report(args, reprise::Status::error("gles-bench: --frames must be at least 1"), {});
    return report(args, parsed, run(scene, sizes, frames));
}
