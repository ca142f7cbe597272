// reprise upsample — spatio-temporal upsampling (Herzog et al. 2010) of low-resolution jittered
// colour to full resolution, guided by the full-resolution G-buffer (reprise render --lowres).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "args.hpp"
#include "commands.hpp"
#include "outputs.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/core/memory_limit.hpp"
#include "reprise/core/metrics.hpp"
#include "reprise/gpu/upsampler.hpp"
#include "reprise/warp/upsample.hpp"

namespace reprise::cli {

namespace {

struct UpsampleJob {
    std::string in, low, out;
    bool spatial_only = false, no_steering = false, no_id_test = false, radial = false;
    double history_weight = 1.0;
    double gamma_max = 4.0, max_history_weight = 16.0, gradient_gain = 1.0, history_clamp = 0.25;
    bool overwrite_inputs = false;
    std::string line, backend = "cpu";
};

Status run_upsample(const UpsampleJob& job) {
    if (job.out.empty()) return Status::error("--out DIR is required");
    if (job.in.empty()) return Status::error("--in DIR is required");
    if (!(job.gamma_max >= 0.0 && job.gamma_max <= 1000.0))
        return Status::error("--gamma-max must be in [0, 1000]");
    if (!(job.max_history_weight > 0.0 && job.max_history_weight <= 1e6))
        return Status::error("--max-history-weight must be in (0, 1e6]");
    if (!(job.gradient_gain >= 0.0 && job.gradient_gain <= 1e3))
        return Status::error("--gradient-gain must be in [0, 1000]");
    if (!(job.history_clamp <= 1e3)) return Status::error("--history-clamp must be at most 1000");
    if (!(job.history_weight >= 0.0 && job.history_weight <= 1.0))
        return Status::error("--history-weight must be in [0, 1]");
    if (job.backend != "cpu" && job.backend != "gles")
        return Status::error("--backend '" + job.backend + "': expected cpu or gles");
    const std::string low_dir = job.low.empty() ? job.in + "/lowres" : job.low;
    Sequence full_sequence, low_sequence;
    REPRISE_TRY(open_sequence(job.in, full_sequence));
    REPRISE_TRY(open_sequence(low_dir, low_sequence));
    if (low_sequence.files.size() < full_sequence.files.size())
        return Status::error(low_dir + ": " + std::to_string(low_sequence.files.size()) +
                             " low-resolution frames for " +
                             std::to_string(full_sequence.files.size()) + " full-resolution ones");
    const warp::UpsampleOptions options{
        .history_weight = job.spatial_only ? 0.0f : float(job.history_weight),
        .max_history_weight = float(job.max_history_weight),
        .gamma_max = float(job.gamma_max),
        .gradient_steering = !job.no_steering,
        .id_test = !job.no_id_test,
        .gradient_gain = float(job.gradient_gain),
        .history_clamp = float(job.history_clamp),
        .separable_filter = !job.radial,
    };
    warp::SpatioTemporalUpsampler upsampler(options);
    // --backend gles: the same passes as OpenGL ES compute shaders.
    std::unique_ptr<gpu::Context> gpu;
    std::unique_ptr<gpu::Upsampler> gpu_upsampler;
    if (job.backend == "gles") {
        REPRISE_TRY(gpu::Context::create(gpu));
        REPRISE_TRY(gpu::Upsampler::create(*gpu, options, gpu_upsampler));
    }
    gpu::Timings gpu_total;
    OutputFolder output;
    REPRISE_TRY(output.open(job.out,
                            {.inputs = {job.in, low_dir}, .overwrite_inputs = job.overwrite_inputs},
                            job.line, false));
    Frame full, low;
    Image<glm::vec4> out;
    Image<glm::vec3> truth_display, out_display;
    double busy_ms = 0.0, psnr_sum = 0.0;
    int psnr_count = 0;
    warp::UpsampleStats total;
    NonfiniteRepair repair;
    const std::size_t n = full_sequence.files.size();
    for (std::size_t i = 0; i < n; ++i) {
        REPRISE_TRY(read_frame(full_sequence.files[i], full));
        // History, taps, gradients and the output: measured 298 bytes a full-resolution pixel.
        REPRISE_TRY(check_image_memory(full.width(), full.height(), 300, "upsample"));
        REPRISE_TRY(read_frame(low_sequence.files[i], low));
        const std::string& low_file = low_sequence.files[i];
        if (full.depth.empty() || full.depth.width() != full.width() ||
            full.depth.height() != full.height())
            return Status::error(full_sequence.files[i] + ": needs depth (Z) at the colour's size");
        if (low.width() > full.width() || low.height() > full.height())
            return Status::error(low_file + ": " + std::to_string(low.width()) + "x" +
                                 std::to_string(low.height()) + " is larger than the full frame");
        const glm::vec2 jitter =
            low.camera.jitter * glm::vec2(float(full.width()) / float(low.width()),
                                          float(full.height()) / float(low.height()));
        if (!std::isfinite(jitter.x) || !std::isfinite(jitter.y) || std::abs(jitter.x) > 1e4f ||
            std::abs(jitter.y) > 1e4f)
            return Status::error(low_file + ": reprise:jitter is not a finite pixel offset");
        const std::size_t guide_depth = repair.repair_depth(full.depth.view());
        const std::size_t guide_motion = repair.repair_motion(full.motion.view());
        const std::size_t guide_normal = repair.repair_normal(full.normal.view());
        GBufferView guides = full.view();
        if (full.motion.width() != full.width() || full.motion.height() != full.height())
            guides.motion = {};
        if (full.normal.width() != full.width() || full.normal.height() != full.height())
            guides.normal = {};
        if (full.id.width() != full.width() || full.id.height() != full.height()) guides.id = {};
        out.resize(full.width(), full.height());
        warp::UpsampleStats stats;
        const auto start = std::chrono::steady_clock::now();
        if (gpu_upsampler) {
            REPRISE_TRY(
                gpu_upsampler->upsample(low.color.view(), jitter, guides, out.view(), &stats));
            gpu_total.upload_ms += gpu_upsampler->timings().upload_ms;
            gpu_total.compute_ms += gpu_upsampler->timings().compute_ms;
            gpu_total.download_ms += gpu_upsampler->timings().download_ms;
        } else {
            upsampler.upsample(low.color.view(), jitter, guides, out.view(), &stats);
        }
        busy_ms +=
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        total.history_rejected += stats.history_rejected;
        total.history_used += stats.history_used;
        total.nonfinite_samples += stats.nonfinite_samples;
        total.unresolved += stats.unresolved;
        // The guides are written with the result: repaired here (the upsampler saw them clean).
        NonfiniteCounts found = stats.nonfinite;
        found.depth += guide_depth, found.motion += guide_motion, found.normal += guide_normal;
        found.frames = found.total() > 0;
        total.nonfinite += found;
        // The full frame's own colour, when rendered, is the truth the result is measured against.
        truth_display.resize(full.width(), full.height());
        out_display.resize(full.width(), full.height());
        to_display(full.color.view(), truth_display.view());
        to_display(out.view(), out_display.view());
        const double p = psnr(truth_display.view(), out_display.view());
        if (std::isfinite(p)) {
            psnr_sum += p;
            ++psnr_count;
        }
        std::swap(full.color, out);
        REPRISE_TRY(output.write(int(i), full));
        std::fprintf(stderr, "\r[upsample] %zu/%zu  %.2f dB", i + 1, n, p);
    }
    REPRISE_TRY(output.finish());
    std::fprintf(stderr, "\n");
    std::printf("upsample %zu frames (%s) -> %s\n", n,
                job.spatial_only  ? "spatial only"
                : job.no_steering ? "history, no steering"
                                  : "spatio-temporal",
                job.out.c_str());
    std::printf(
        "  %.2f ms per frame (without file I/O); mean PSNR against the full-resolution colour %.2f "
        "dB\n",
        n ? busy_ms / double(n) : 0.0, psnr_count ? psnr_sum / psnr_count : 0.0);
    std::printf(
        "  history used %lld, rejected %lld pixels; %lld non-finite samples; %lld unresolved "
        "pixels\n",
        (long long)total.history_used, (long long)total.history_rejected,
        (long long)total.nonfinite_samples, (long long)total.unresolved);
    if (gpu && n > 0)
        std::printf("  on the GPU (%s): upload %.2f, compute %.2f, download %.2f ms a frame\n",
                    gpu->description().c_str(), gpu_total.upload_ms / double(n),
                    gpu_total.compute_ms / double(n), gpu_total.download_ms / double(n));
    if (total.nonfinite.total() > 0)
        std::fprintf(stderr, "[upsample] input: %s\n", describe_nonfinite(total.nonfinite).c_str());
    return {};
}

}  // namespace

int command_upsample(int argc, char** argv) {
    UpsampleJob job;
    Args args(
        "upsample",
        "Spatio-temporal upsampling (Herzog et al. 2010) of low-resolution jittered colour to the "
        "full\nresolution of its G-buffer: --in is a sequence from `reprise render --lowres 2|4` "
        "(full G-buffer\nframes, low colour in IN/lowres with reprise:jitter in its own pixels). "
        "Writes the full frames\nwith the upsampled colour and prints its PSNR against the "
        "full frames' own colour.");
    args.option("--in", &job.in, "full-resolution G-buffer sequence (required)");
    args.option("--low", &job.low, "low-resolution colour sequence (default IN/lowres)");
    args.option("--backend", &job.backend,
                "cpu | gles (default cpu); gles: the same passes as OpenGL ES compute shaders");
    args.option("--out", &job.out, "output folder (required)");
    args.option("--history-weight", &job.history_weight,
                "a of the temporal weight, 0..1 (default 1)");
    args.option("--gamma-max", &job.gamma_max,
                "largest fall-off of the image-space filter (default 4, the paper's)");
    args.option("--max-history-weight", &job.max_history_weight,
                "cap on the history weight (default 16)");
    args.option("--gradient-gain", &job.gradient_gain,
                "factor on the temporal gradient (default 1)");
    args.option("--history-clamp", &job.history_clamp,
                "clamp the history to the samples' colour box widened by this fraction (default "
                "0.25; < 0: off, as the paper)");
    args.flag("--spatial-only", &job.spatial_only, "joint bilateral upsampling without history");
    args.flag("--no-steering", &job.no_steering,
              "a fixed history fall-off (0.9) instead of temporal gradients");
    args.flag("--radial", &job.radial,
              "the paper's radial image-space filter over the low pixel's diagonal (default: a "
              "separable tent)");
    args.flag("--no-id-test", &job.no_id_test, "ignore object ids (depth and normals only)");
    args.flag("--overwrite-inputs", &job.overwrite_inputs,
              "allow --out where the inputs are (written after all are read)");
    Status parsed = args.parse(argc, argv);
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    job.line = args.given_line({});
    return report(args, parsed, run_upsample(job));
}

}  // namespace reprise::cli
