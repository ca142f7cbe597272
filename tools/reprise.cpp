// reprise: one executable, one subcommand per job.
#include <cstdio>
#include <string_view>

#include "commands.hpp"

namespace {

struct Command {
    const char* name;
    int (*run)(int, char**);
    const char* summary;
};

constexpr Command kCommands[] = {
    {"render", reprise::cli::command_render, "render a scene's G-buffer sequence to EXR"},
    {"scenes", reprise::cli::command_scenes, "list the built-in scenes"},
    {"info", reprise::cli::command_info,
     "channels, size, camera and frame rate of EXR frames, or of an .rps stream"},
    {"metrics", reprise::cli::command_metrics, "PSNR, SSIM and FLIP of a sequence against another"},
    {"export", reprise::cli::command_export, "a sequence as PNG contact sheet or MP4"},
    {"fruc", reprise::cli::command_fruc,
     "frame-rate upconversion (interpolate or extrapolate) x K"},
    {"stereo", reprise::cli::command_stereo,
     "the other eye of a sequence by depth warping (OUT/left, OUT/right)"},
    {"encode", reprise::cli::command_encode, "encode a sequence with the scene-aware codec (.rps)"},
    {"decode", reprise::cli::command_decode, "decode an .rps stream into an EXR sequence"},
    {"serve", reprise::cli::command_serve,
     "stream a scene to clients (render from their poses, encode, send)"},
    {"connect", reprise::cli::command_connect,
     "connect to a server, display its stream extrapolated to the display rate"},
    {"upsample", reprise::cli::command_upsample,
     "low-resolution jittered colour to full resolution (Herzog 2010)"},
    {"bench", reprise::cli::command_bench, "benchmarks (render, exr, reproject, grid, fill, fruc)"},
};

void print_usage(FILE* out) {
    std::fputs("usage: reprise COMMAND [options]   (reprise COMMAND --help for each)\n\n", out);
    for (const Command& c : kCommands) std::fprintf(out, "  %-9s %s\n", c.name, c.summary);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        print_usage(stderr);
        return 2;
    }
    std::string_view name = argv[1];
    if (name == "-h" || name == "--help" || name == "help") {
        print_usage(stdout);
        return 0;
    }
    for (const Command& c : kCommands)
        if (name == c.name) return c.run(argc - 2, argv + 2);
    std::fprintf(stderr, "reprise: unknown command '%s'\n", argv[1]);
    print_usage(stderr);
    return 2;
}
