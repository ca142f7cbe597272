// reprise fruc — frame-rate upconversion of an EXR sequence.
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "args.hpp"
#include "commands.hpp"
#include "flow_motion.hpp"
#include "fruc_options.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/warp/fruc.hpp"

namespace reprise::cli {

namespace {

struct FrucJob {
    std::string in, out;
    int factor = 2;
    std::string mode = "interpolate", warp = "grid", fill = "pullpush";
    std::string layout = "reprise";
};

Status run_fruc(const FrucJob& job) {
    if (job.factor < 1 || job.factor > 16) return Status::error("--factor must be in 1..16");
    if (job.out.empty()) return Status::error("--out DIR is required");
    warp::FrucOptions options;
    REPRISE_TRY(parse_fruc_options(job.mode, job.warp, job.fill, options));
    WriteOptions write;
    if (job.layout == "blender")
        write.layout = ExrLayout::Blender;
    else if (job.layout != "reprise")
        return Status::error("--layout must be reprise or blender, not '" + job.layout + "'");
    Sequence sequence;
    REPRISE_TRY(open_sequence(job.in, sequence));
    std::error_code ec;
    std::filesystem::create_directories(job.out, ec);
    if (ec) return Status::error(job.out + ": cannot create the folder: " + ec.message());

    warp::FrameRateConverter converter(job.factor, options);
    FlowMotion flow;
    bool estimating = false;
    Frame in, out;
    int written = 0;
    double busy_ms = 0.0;
    const std::size_t n = sequence.files.size();
    for (std::size_t i = 0; i < n; ++i) {
        REPRISE_TRY(read_frame(sequence.files[i], in));
        if (in.fps <= 0) in.fps = sequence.fps;
        if (i == 0 && (in.motion.empty() || in.depth.empty())) {
            // Said once, before any work: what the input lacks and what stands in for it.
            if (in.motion.empty())
                std::fprintf(stderr,
                             "[fruc] %s: no motion channels (motion.x, motion.y): motion is "
                             "estimated by optical flow (OpenCV DIS) between consecutive frames\n",
                             sequence.files[i].c_str());
            if (in.depth.empty())
                std::fprintf(stderr,
                             "[fruc] %s: no depth channel (Z): every pixel is given one "
                             "depth, so nothing occludes anything\n",
                             sequence.files[i].c_str());
            estimating = true;
        }
        if (estimating) flow.complete(in);
        auto start = std::chrono::steady_clock::now();
        REPRISE_TRY(converter.send(in));
        busy_ms +=
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        while (converter.receive(out))
            REPRISE_TRY(write_frame(frame_path(job.out, written++), out, write));
        std::fprintf(stderr, "\r[fruc] %zu/%zu input frames, %d written", i + 1, n, written);
    }
    const warp::FrucCounters& c = converter.counters();
    std::fprintf(stderr, "\n");
    std::printf("fruc %s x%d, warp %s, fill %s: %zu inputs -> %d frames in %s\n", job.mode.c_str(),
                job.factor, job.warp.c_str(), job.fill.c_str(), c.inputs, written, job.out.c_str());
    std::printf("  made %zu frames, %.2f ms each (without file I/O)\n", c.outputs,
                c.outputs ? busy_ms / double(c.outputs) : 0.0);
    std::printf(
        "  skipped: %zu still frames copied, %zu fills (no holes), %zu dynamic layers (nothing "
        "moving), "
        "%zu true-motion passes (linear motion)\n",
        c.copied_still, c.fills_skipped, c.dynamic_skipped, c.linear_motion);
    std::printf(
        "  done: %zu fills (%zu hole pixels), %zu dynamic layers, %zu grid cells, %zu cuts, "
        "%zu true-motion frames\n",
        c.fills, c.hole_pixels, c.dynamic_layers, c.grid_cells, c.cuts, c.true_motion);
    return {};
}

}  // namespace

int command_fruc(int argc, char** argv) {
    FrucJob job;
    Args args("fruc",
              "Frame-rate upconversion: writes an EXR sequence at K times the input rate.\n"
              "interpolate: K-1 frames between each pair (one frame of latency); extrapolate: K-1 "
              "frames\nbeyond each frame from it alone (no latency).");
    args.option("--in", &job.in, "input sequence (folder of EXR frames)");
    args.option("--factor", &job.factor, "K, output frames per input frame (default 2)");
    args.option("--mode", &job.mode, "interpolate | extrapolate (default interpolate)");
    args.option(
        "--warp", &job.warp,
        "reverse | splat | grid (default grid; grid-bicubic, grid-bilinear pick its colour fetch)");
    args.option("--fill", &job.fill, "pullpush | andreev | none (default pullpush)");
    args.option("--out", &job.out, "output folder");
    args.option("--layout", &job.layout,
                "EXR channel names: reprise | blender (ViewLayer.Combined.R..., opens in "
                "Blender)");
    Status parsed = args.parse(argc, argv);
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    if (job.in.empty()) return report(args, Status::error("fruc: --in DIR is required"), {});
    return report(args, parsed, run_fruc(job));
}

}  // namespace reprise::cli
