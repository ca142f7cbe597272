// reprise bench paths --backend gles: the stages the GPU backend has (reverse reprojection,
// pull-push), each beside its CPU reference on the same frames in the same run; the GPU's
// upload, compute and download apart, and how far its result is from the CPU's.
#include <cstdio>
#include <string>
#include <vector>

#include "bench.hpp"
#include "bench_report.hpp"
#include "reprise/core/metrics.hpp"
#include "reprise/gpu/context.hpp"
#include "reprise/warp/fill.hpp"
#include "reprise/warp/reproject.hpp"

namespace reprise::cli {

namespace {

// One stage's timings on both backends, and the GPU result's distance from the CPU's.
struct StageTimes {
    const char* name;
    Timing cpu, upload, compute, download, total;
    double worst_db = INFINITY;
};

void record(StageTimes& stage, const gpu::Timings& t, double total_ms) {
    stage.upload.ms.push_back(t.upload_ms);
    stage.compute.ms.push_back(t.compute_ms);
    stage.download.ms.push_back(t.download_ms);
    stage.total.ms.push_back(total_ms);
}

double display_psnr(const Image<glm::vec4>& a, const Image<glm::vec4>& b) {
    Image<glm::vec3> da(a.width(), a.height()), db(b.width(), b.height());
    to_display(a.view(), da.view());
    to_display(b.view(), db.view());
    return psnr(da.view(), db.view());
}

}  // namespace

Status bench_gles_stages(const std::vector<Frame>& frames, const std::string& size) {
    std::unique_ptr<gpu::Context> context;
    REPRISE_TRY(gpu::Context::create(context));
    const int w = frames[0].width(), h = frames[0].height();
    Image<glm::vec4> cpu_out(w, h), gpu_out(w, h), cpu_filled(w, h), gpu_filled(w, h);
    Image<uint8_t> cpu_hit(w, h), gpu_hit(w, h);
    warp::PullPush pull_push;
    StageTimes stages[2] = {{"reproject RGBA"}, {"pull-push (depth)"}};
    warp::ReprojectCounts counts;
    warp::FillStats stats;
    // Frame i reprojected into frame i - 1, then its misses filled; the first pair untimed (the
    // driver compiles its shader variants there).
    for (std::size_t i = 1; i < frames.size(); ++i) {
        const bool timing = i >= 2;
        const Frame &current = frames[i], &previous = frames[i - 1];
        const warp::ConstPayload payload = warp::payload_of(previous.color.view());
        Timing scratch;
        Timing& cpu_reproject = timing ? stages[0].cpu : scratch;
        time_once(cpu_reproject, [&] {
            counts = warp::reproject(current, previous, payload, warp::payload_of(cpu_out.view()),
                                     cpu_hit.view());
        });
        Status status;
        Timing total;
        time_once(total, [&] {
            status =
                context->reproject(current, previous, payload, warp::payload_of(gpu_out.view()),
                                   gpu_hit.view(), {}, counts);
        });
        REPRISE_TRY(status);
        if (timing) record(stages[0], context->timings(), total.ms[0]);
        stages[0].worst_db = std::min(stages[0].worst_db, display_psnr(cpu_out, gpu_out));

        cpu_filled = cpu_out;
        gpu_filled = cpu_out;
        Timing& cpu_fill = timing ? stages[1].cpu : scratch;
        time_once(cpu_fill,
                  [&] { pull_push.fill(cpu_filled.view(), cpu_hit.view(), current.depth.view()); });
        Timing fill_total;
        time_once(fill_total, [&] {
            status = context->fill(gpu_filled.view(), cpu_hit.view(), current.depth.view(), stats);
        });
        REPRISE_TRY(status);
        if (timing) record(stages[1], context->timings(), fill_total.ms[0]);
        stages[1].worst_db = std::min(stages[1].worst_db, display_psnr(cpu_filled, gpu_filled));
    }
    std::printf("gles: %s; GPU columns are medians; texture path = compute alone\n",
                context->description().c_str());
    std::printf("%-10s %-20s %9s %9s %9s %9s %9s %9s %9s %8s\n", "size", "stage", "cpu best",
                "cpu med", "upload", "compute", "download", "gles med", "tex/cpu", "dB vs cpu");
    for (const StageTimes& s : stages)
        std::printf("%-10s %-20s %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f %8.2fx %8.1f\n", size.c_str(),
                    s.name, s.cpu.best(), s.cpu.median(), s.upload.median(), s.compute.median(),
                    s.download.median(), s.total.median(), s.compute.median() / s.cpu.median(),
                    s.worst_db);
    return {};
}

}  // namespace reprise::cli
