// reprise fruc — frame-rate upconversion of an EXR sequence.
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "args.hpp"
#include "commands.hpp"
#include "flow_motion.hpp"
#include "fruc_options.hpp"
#include "input_range.hpp"
#include "outputs.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/gpu/fruc_backend.hpp"
#include "reprise/warp/fruc.hpp"

namespace reprise::cli {

namespace {

struct FrucJob {
    std::string in, out;
    int factor = 2;
    std::string mode = "interpolate", warp = "grid", fill = "pullpush";
    std::string layout = "reprise";
    std::string refine = "on";
    std::string true_motion = "on";
    std::string silhouettes = "widen";
    std::string blend = "perceptual";
    std::string backend = "cpu";
    double refine_share = 1.0;
    int border_run = warp::kMadeFrameBorderRun;
    std::string ui;             // a UI sequence beside the input (its colour: premultiplied RGBA)
    bool ui_composite = false;  // draw the UI into the output colour
    double budget_db = 0.0;     // auto: the PSNR to reach (0: within slack of the best expected)
    bool resume = false, overwrite_inputs = false;
    std::string range;  // --range A:B: input pairs A..B only
    std::string line;   // the options given, recorded for --resume
};

// Resuming at output frame `on_disk` starts at the input whose pair makes it, two inputs early:
// the converter's state (the previous frame and whether it starts a shot) comes from those.
std::size_t resume_input(int on_disk, int factor, warp::FrucMode mode) {
    const int first =
        mode == warp::FrucMode::Interpolate ? (on_disk + factor - 1) / factor : on_disk / factor;
    return std::size_t(std::max(0, first - 2));
}

// The output frames input `i` makes when it is sent after input i - 1: interpolation gives the
// frames between them and input i itself, extrapolation input i and the frames beyond it.
struct OutputSpan {
    int begin, end;
};
OutputSpan outputs_of(std::size_t i, int factor, warp::FrucMode mode) {
    const int k = factor, j = int(i);
    if (mode == warp::FrucMode::Extrapolate) return {j * k, (j + 1) * k};
    return {j == 0 ? 0 : (j - 1) * k + 1, j * k + 1};
}

Status run_fruc(const FrucJob& job) {
    if (Status s = warp::check_fruc_factor(job.factor); !s.ok())
        return Status::error("--" + s.message());
    if (job.out.empty()) return Status::error("--out DIR is required");
    warp::FrucOptions options;
    REPRISE_TRY(parse_fruc_options(job.mode, job.warp, job.fill, options));
    REPRISE_TRY(parse_refine(job.refine, options));
    if (!(job.refine_share >= 0.0 && job.refine_share <= 1.0))
        return Status::error("--refine-share must be in 0..1");
    options.refine.max_flow_share = float(job.refine_share);
    if (job.border_run < 0) return Status::error("--border-run must be >= 0");
    options.border_run = job.border_run;
    if (job.true_motion != "on" && job.true_motion != "off")
        return Status::error("--true-motion '" + job.true_motion + "': expected on or off");
    options.true_motion = job.true_motion == "on";
    if (job.silhouettes != "widen" && job.silhouettes != "keep")
        return Status::error("--silhouettes '" + job.silhouettes + "': expected widen or keep");
    options.widen_silhouettes = job.silhouettes == "widen";
    if (job.blend != "perceptual" && job.blend != "linear")
        return Status::error("--blend '" + job.blend + "': expected perceptual or linear");
    options.perceptual = job.blend == "perceptual";
    if (job.backend != "cpu" && job.backend != "gles")
        return Status::error("--backend '" + job.backend + "': expected cpu or gles");
    std::unique_ptr<gpu::Context> gpu;
    std::unique_ptr<gpu::FrucBackend> backend;
    if (job.backend == "gles") {
        if (const Status s = gpu::FrucBackend::check(options, options.splat); !s.ok())
            return Status::error("--backend gles: " + s.message());
        REPRISE_TRY(gpu::Context::create(gpu));
        backend = std::make_unique<gpu::FrucBackend>(*gpu, options.splat);
        options.backend = backend.get();
    }
    WriteOptions write;
    if (job.layout == "blender")
        write.layout = ExrLayout::Blender;
    else if (job.layout != "reprise")
        return Status::error("--layout must be reprise or blender, not '" + job.layout + "'");
    options.composite_ui = job.ui_composite;
    if (job.budget_db < 0.0 || job.budget_db > 100.0)
        return Status::error("--budget-db must be in 0..100");
    options.auto_choice.budget_db = float(job.budget_db);
    Sequence sequence, ui_sequence;
    REPRISE_TRY(open_sequence(job.in, sequence));
    if (!job.ui.empty()) {
        REPRISE_TRY(open_sequence(job.ui, ui_sequence));
        if (ui_sequence.files.size() < sequence.files.size())
            return Status::error("--ui " + job.ui + ": " +
                                 std::to_string(ui_sequence.files.size()) + " frames for " +
                                 std::to_string(sequence.files.size()) + " input frames");
    }
    REPRISE_TRY(check_one_size(sequence, "fruc"));
    OutputRules rules{.inputs = {job.in}, .overwrite_inputs = job.overwrite_inputs};
    if (!job.ui.empty()) rules.inputs.push_back(job.ui);
    // A range of input pairs A..B writes the frames inputs A+1..B+1 make (and input 0's when A
    // is 0), so that ranges that meet cover a whole run's frames once. Its converter starts two
    // inputs early, as a resumed run does: input A is the previous frame of the first pair and
    // the cut test between A-1 and A says whether A starts a shot.
    InputRange range;
    REPRISE_TRY(parse_input_range(job.range, sequence.files.empty() ? 0 : sequence.files.size() - 1,
                                  "input pairs", range));
    if (!range.all && job.resume)
        return Status::error("--range and --resume cannot be combined (run the range again)");
    OutputFolder output;
    REPRISE_TRY(output.open(job.out, rules, range.all ? job.line : std::string(), job.resume));
    const std::size_t n = range.all ? sequence.files.size() : range.last + 2;
    std::size_t first = resume_input(output.frames_on_disk(), job.factor, options.mode);
    OutputSpan wanted{0, outputs_of(n - 1, job.factor, options.mode).end};
    if (!range.all) {
        first = range.first == 0 ? 0 : range.first - 1;
        wanted.begin =
            range.first == 0 ? 0 : outputs_of(range.first + 1, job.factor, options.mode).begin;
    }

    warp::FrameRateConverter converter;
    REPRISE_TRY(warp::FrameRateConverter::create(job.factor, options, converter));
    FlowMotion flow;
    bool estimating = false;
    Frame in, out, ui_frame;
    int made = int(first) * job.factor;  // the index of the next output frame
    int written = 0;                     // by this range
    double busy_ms = 0.0;
    if (output.frames_on_disk() > 0)
        std::fprintf(stderr, "[fruc] resuming: %d frames on disk, restarting at input %zu\n",
                     output.frames_on_disk(), first);
    for (std::size_t i = first; i < n; ++i) {
        REPRISE_TRY(read_frame(sequence, i, in));
        if (in.fps <= 0) in.fps = sequence.fps;
        if (i == first && (in.motion.empty() || in.depth.empty())) {
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
        if (!job.ui.empty()) {
            REPRISE_TRY(read_frame(ui_sequence.files[i], ui_frame));
            if (ui_frame.width() != in.width() || ui_frame.height() != in.height())
                return Status::error(ui_sequence.files[i] + ": UI frame size differs from " +
                                     sequence.files[i]);
            std::swap(in.ui, ui_frame.color);
        }
        if (i == first && !in.ui.empty())
            std::fprintf(stderr,
                         "[fruc] UI layer found (%s): the scene is warped without it, each made "
                         "frame gets the nearest input's UI unwarped%s\n",
                         job.ui.empty() ? "ui.R ui.G ui.B ui.A channels" : job.ui.c_str(),
                         job.ui_composite ? ", drawn into the colour" : ", in its ui channels");
        auto start = std::chrono::steady_clock::now();
        REPRISE_TRY(converter.send(std::move(in)));  // `in` gets buffers back to read into
        busy_ms +=
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        for (; converter.receive(out); ++made)
            if (made >= wanted.begin && made < wanted.end) {
                REPRISE_TRY(output.write(made, out, write));
                ++written;
            }
        std::fprintf(stderr, "\r[fruc] %zu/%zu input frames, %d written", i + 1, n,
                     range.all ? made : written);
    }
    REPRISE_TRY(output.finish());
    const warp::FrucCounters& c = converter.counters();
    std::fprintf(stderr, "\n");
    std::printf("fruc %s x%d, warp %s, fill %s, %s: %zu inputs -> %d frames in %s\n",
                job.mode.c_str(), job.factor, job.warp.c_str(), job.fill.c_str(),
                job.backend.c_str(), c.inputs, range.all ? made : written, job.out.c_str());
    if (!range.all)
        std::printf("  range: input pairs %zu..%zu, frames %d..%d (read from input %zu on)\n",
                    range.first, range.last, wanted.begin, wanted.end - 1, first);
    std::printf("  made %zu frames, %.2f ms each (without file I/O)\n", c.outputs,
                c.outputs ? busy_ms / double(c.outputs) : 0.0);
    if (backend && backend->frames() > 0) {
        const double n_gpu = double(backend->frames());
        std::printf(
            "  gles: %zu frames on the GPU, cpu %.2f, upload %.2f, compute %.2f, download %.2f ms "
            "each\n",
            backend->frames(), backend->total().cpu_ms / n_gpu, backend->total().upload_ms / n_gpu,
            backend->total().compute_ms / n_gpu, backend->total().download_ms / n_gpu);
    }
    std::printf(
        "  skipped: %zu still frames copied, %zu fills (no holes), %zu dynamic layers (nothing "
        "moving), "
        "%zu true-motion passes (linear motion), %zu cut tests (the camera said)\n",
        c.copied_still, c.fills_skipped, c.dynamic_skipped, c.linear_motion, c.cut_tests_skipped);
    std::printf(
        "  done: %zu fills (%zu hole pixels, %zu border pixels continued first), %zu dynamic "
        "layers, %zu grid cells, %zu cuts, %zu true-motion frames, %zu input pixels with a "
        "nearer neighbour's surface\n",
        c.fills, c.hole_pixels, c.border_pixels, c.dynamic_layers, c.grid_cells, c.cuts,
        c.true_motion, c.silhouette_pixels);
    if (options.mode == warp::FrucMode::Interpolate && options.refine.enabled)
        std::printf(
            "  refinement: %zu frames refined, %zu skipped (sides agree), %zu tiles (%zu left out "
            "past the flow budget), flow on %zu px, %zu px refined, %.2f ms per made frame\n",
            c.refined_frames, c.refine_skipped, c.refine_tiles, c.refine_tiles_left_out,
            c.flow_pixels, c.refined_pixels, c.outputs ? c.refine_ms / double(c.outputs) : 0.0);
    if (options.warp == warp::WarpMethod::Auto || options.fill == warp::FillMethod::Auto) {
        if (job.budget_db > 0)
            std::printf(
                "  auto (budget %.1f dB): per candidate, frames chosen for and frames left "
                "out of although expected higher\n",
                job.budget_db);
        else
            std::printf(
                "  auto (cheapest within %.2f dB of the best expected): per candidate, "
                "frames chosen for and frames left out of although expected higher\n",
                double(options.auto_choice.slack_db));
        std::printf("%s", auto_choice_summary(c).c_str());
    }
    if (c.nonfinite.total() > 0)
        std::fprintf(stderr, "[fruc] input: %s\n", describe_nonfinite(c.nonfinite).c_str());
    if (c.ui_frames > 0)
        std::printf("  UI layer: %zu made frames took the nearest input's UI, unwarped\n",
                    c.ui_frames);
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
    args.option("--refine", &job.refine,
                "on | off (default on): interpolation refines motion by optical flow where the "
                "warped\nsides disagree (moving shadows, reflections, highlights)");
    args.option("--refine-share", &job.refine_share,
                "refinement: largest share of the frame's pixels the flow runs on (default 1); "
                "the\ntiles past it are left out, those that disagree most per pixel go first");
    args.option("--border-run", &job.border_run,
                "px of each row's border strip a made frame continues from the row before its "
                "fill\n(default " +
                    std::to_string(warp::kMadeFrameBorderRun) + "; 0: the fill alone)");
    args.option("--true-motion", &job.true_motion,
                "on | off (default on): interpolation moves each side where it truly is at the "
                "in-between\ninstant (off: each follows its motion linearly)");
    args.option("--silhouettes", &job.silhouettes,
                "widen | keep (default widen): pixels beside a nearer surface warp with it, so "
                "the colour\nanti-aliasing blended into them travels with the silhouette");
    args.option("--blend", &job.blend,
                "perceptual | linear (default perceptual): colour warped, blended and filled as "
                "the square\nroot of linear light (close to the display's scale), or in linear "
                "light");
    args.option("--backend", &job.backend,
                "cpu | gles (default cpu); gles: the made frames on OpenGL ES (--warp grid, splat "
                "or reverse);\ninterpolated with --fill pullpush (refinement's optical flow on "
                "the CPU), extrapolated\nwith --fill pullpush or none");
    args.option("--warp", &job.warp,
                "reverse | splat | grid | auto (default grid; grid-bicubic, grid-bilinear pick "
                "its colour\nfetch; auto: chosen per frame)");
    args.option("--fill", &job.fill,
                "pullpush | andreev | patch | none | auto (default pullpush); patch: "
                "frequency-selective reconstruction, slow");
    args.option("--budget-db", &job.budget_db,
                "auto: the PSNR (dB) a made frame should reach; the cheapest setting expected to "
                "reach it\nis taken (default 0: the cheapest within 0.25 dB of the best expected)");
    args.option("--out", &job.out, "output folder");
    args.option("--layout", &job.layout,
                "EXR channel names: reprise | blender (ViewLayer.Combined.R..., opens in "
                "Blender)");
    args.option("--ui", &job.ui,
                "a UI/HUD sequence beside --in (colour = premultiplied RGBA), kept out of the "
                "warp;\nframes with ui.R ui.G ui.B ui.A channels need no flag");
    args.flag("--ui-composite", &job.ui_composite,
              "draw the UI into the output colour (default: keep it in ui.* channels)");
    args.option("--range", &job.range,
                "A:B: input pairs A..B only (pair i: inputs i and i+1), writing the frames "
                "they make\n(and input 0 when A is 0); ranges that meet give a whole run's "
                "bytes (a farm's chunks)");
    args.flag("--resume", &job.resume,
              "continue an interrupted run of the same arguments from the frames in --out");
    args.flag("--overwrite-inputs", &job.overwrite_inputs,
              "allow --out where the inputs are (written after all are read)");
    Status parsed = args.parse(argc, argv);
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    job.line = args.given_line({"--resume"});
    if (job.in.empty()) return report(args, Status::error("fruc: --in DIR is required"), {});
    return report(args, parsed, run_fruc(job));
}

}  // namespace reprise::cli
