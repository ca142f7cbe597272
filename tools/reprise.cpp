// reprise: one executable, one subcommand per job.
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "commands.hpp"
#include "reprise/core/memory_limit.hpp"

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
    {"batch", reprise::cli::command_batch,
     "fruc or stereo of one sequence in chunks over a Dask cluster (python3-distributed)"},
    {"bench", reprise::cli::command_bench, "benchmarks (render, exr, reproject, grid, fill, fruc)"},
};

void print_usage(FILE* out) {
    std::fputs(
        "usage: reprise COMMAND [options]   (reprise COMMAND --help for each; reprise "
        "--version)\n\n",
        out);
    for (const Command& c : kCommands) std::fprintf(out, "  %-9s %s\n", c.name, c.summary);
    std::fputs(
        "\nAny command takes --max-memory SIZE (8G, 512M, bytes; default 4G): what one call "
        "may allocate,\nchecked against an estimate before allocating.\n",
        out);
}

// Takes --max-memory SIZE (or --max-memory=SIZE) out of the arguments, wherever it stands, and
// sets the process's memory limit. Returns false after printing the error.
bool take_max_memory(int& argc, char** argv) {
    reprise::set_memory_limit_hint("--max-memory to change");
    int kept = 1;
    for (int i = 1; i < argc; ++i) {
        const std::string_view arg = argv[i];
        std::string value;
        if (arg == "--max-memory") {
            if (i + 1 >= argc) {
                std::fputs("reprise: --max-memory: missing value (e.g. 8G or 512M)\n", stderr);
                return false;
            }
            value = argv[++i];
        } else if (arg.starts_with("--max-memory=")) {
            value = arg.substr(std::strlen("--max-memory="));
        } else {
            argv[kept++] = argv[i];
            continue;
        }
        std::uint64_t bytes = 0;
        const reprise::Status parsed = reprise::parse_bytes(value, bytes);
        if (!parsed.ok()) {
            std::fprintf(stderr, "reprise: --max-memory: %s\n", parsed.message().c_str());
            return false;
        }
        reprise::set_memory_limit(bytes);
    }
    argc = kept;
    argv[argc] = nullptr;
    return true;
}

// Frame-sized working buffers come and go every frame. glibc's defaults hand large freed blocks
// back to the system and map the next ones afresh, so every frame paid its page faults again
// (bench codec's 1080p speed run: encode 111-123 -> 73-77 ms, decode 90-100 -> 66-70 ms on a
// 2-core virtual machine): keep freed memory in the process for reuse.
void keep_freed_memory() {
#if defined(__GLIBC__)
    mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
    mallopt(M_TOP_PAD, 64 << 20);
#endif
}

}  // namespace

int main(int argc, char** argv) {
    keep_freed_memory();
    if (!take_max_memory(argc, argv)) return 2;
    if (argc < 2) {
        print_usage(stderr);
        return 2;
    }
    std::string_view name = argv[1];
    if (name == "-h" || name == "--help" || name == "help") {
        print_usage(stdout);
        return 0;
    }
    if (name == "--version" || name == "version") {
        std::printf("reprise %s\n", REPRISE_VERSION);
        return 0;
    }
    for (const Command& c : kCommands)
        if (name == c.name) return c.run(argc - 2, argv + 2);
    std::fprintf(stderr, "reprise: unknown command '%s'\n", argv[1]);
    print_usage(stderr);
    return 2;
}
