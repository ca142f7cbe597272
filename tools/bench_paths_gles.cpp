// reprise bench paths --backend gles: the stages the GPU backend has (reverse reprojection,
// pull-push, the forward splat, the stereo eye by splat and by the grid, the in-between frame by
// splat, by the grid and the default one with refinement), each beside its CPU reference on the
// same frames in the same run; the GPU's upload, compute and download apart, the texture entry
// point on textures already on the GPU, and how far the GPU's result is from the CPU's.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <GLES3/gl32.h>
#include "bench.hpp"
#include "timing.hpp"

#include "reprise/core/metrics.hpp"
#include "reprise/gpu/context.hpp"
#include "reprise/gpu/upsampler.hpp"
#include "reprise/stereo/rig.hpp"
#include "reprise/stereo/synthesize.hpp"
#include "reprise/warp/extrapolate.hpp"
#include "reprise/warp/fill.hpp"
#include "reprise/warp/fruc.hpp"
#include "reprise/warp/reproject.hpp"
#include "reprise/warp/splat.hpp"
#include "reprise/warp/upsample.hpp"

namespace reprise::cli {

namespace {

// One stage's timings on both backends, and the GPU result's distance from the CPU's.
struct StageTimes {
    const char* name;
    Timing cpu, prep, upload, compute, download, total, textures;
    double worst_db = INFINITY;
};

void record(StageTimes& stage, const gpu::Timings& t, double total_ms) {
    stage.prep.ms.push_back(t.cpu_ms);
    stage.upload.ms.push_back(t.upload_ms);
    stage.compute.ms.push_back(t.compute_ms);
    stage.download.ms.push_back(t.download_ms);
    stage.total.ms.push_back(total_ms);
}

// Textures made as an application would, deleted with it: the texture entry points' inputs.
struct Textures {
    std::vector<GLuint> names;
    GLuint make(GLenum format, int w, int h, GLenum pixel_format, GLenum type, const void* data) {
        GLuint t = 0;
        glGenTextures(1, &t);
        glBindTexture(GL_TEXTURE_2D, t);
        glTexStorage2D(GL_TEXTURE_2D, 1, format, w, h);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        if (data) glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, pixel_format, type, data);
        names.push_back(t);
        return t;
    }
    gpu::GBufferTextures gbuffer(const Frame& f) {
        const int w = f.width(), h = f.height();
        return {.depth = make(GL_R32F, w, h, GL_RED, GL_FLOAT, f.depth.data()),
                .motion = make(GL_RG32F, w, h, GL_RG, GL_FLOAT, f.motion.data()),
                .id = make(GL_R32UI, w, h, GL_RED_INTEGER, GL_UNSIGNED_INT, f.id.data()),
                .width = w,
                .height = h,
                .camera = f.camera};
    }
    ~Textures() { glDeleteTextures(GLsizei(names.size()), names.data()); }
};

// Extrapolation by the splat and by the grid (pull-push).
const warp::FrucOptions kExtrapolation{.mode = warp::FrucMode::Extrapolate,
                                       .warp = warp::WarpMethod::Splat};
const warp::FrucOptions kGridExtrapolation{.mode = warp::FrucMode::Extrapolate};

// The default in-between frame on the GPU: the grid, true motion, refinement.
const gpu::InterpolateOptions kRefinedBetween{
    .grid = true, .grid_options = warp::FrucOptions{}.grid, .true_motion = true, .refine = {}};

// The stages on textures already on the GPU (the last pair of frames), `runs` times each:
// compute alone, as an application that keeps its frames on the GPU pays it.
struct TextureTimings {
    Timing &reproject, &fill, &eye, &between, &ahead, &grid_eye, &grid_ahead, &grid_between,
        &refined_between;
};
Status time_texture_path(gpu::Context& context, const Frame& current, const Frame& previous,
                         const Image<uint8_t>& hit_mask, int runs, const TextureTimings& timed) {
    context.make_current();
    const int w = current.width(), h = current.height();
    Textures t;
    const gpu::GBufferTextures now = t.gbuffer(current), before = t.gbuffer(previous);
    const GLuint payload = t.make(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT, previous.color.data());
    const GLuint out = t.make(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT, nullptr);
    const GLuint hit = t.make(GL_R32UI, w, h, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
    const GLuint valid = t.make(GL_R8UI, w, h, GL_RED_INTEGER, GL_UNSIGNED_BYTE, hit_mask.data());
    const GLuint filled = t.make(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT, nullptr);
    const GLuint color = t.make(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT, current.color.data());
    const GLuint eye_depth = t.make(GL_R32F, w, h, GL_RED, GL_FLOAT, nullptr);
    const GLuint previous_color =
        t.make(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT, previous.color.data());
    const Camera right = stereo::eye_cameras(current.camera, {}, stereo::Anchor::Left).right;
    warp::ReprojectCounts counts;
    warp::FillStats stats;
    stereo::StereoStats eye_stats;
    for (int i = 0; i <= runs; ++i) {  // the first run untimed
        REPRISE_TRY(context.reproject(now, before, payload, out, hit, {}, counts));
        if (i) timed.reproject.ms.push_back(context.timings().compute_ms);
        REPRISE_TRY(context.fill(out, valid, now.depth, w, h, filled, stats));
        if (i) timed.fill.ms.push_back(context.timings().compute_ms);
        REPRISE_TRY(context.stereo_eye(now, color, right, filled, eye_depth, eye_stats,
                                       {.warp = stereo::StereoWarp::Splat}));
        if (i) timed.eye.ms.push_back(context.timings().compute_ms);
        REPRISE_TRY(context.stereo_eye(now, color, right, filled, eye_depth, eye_stats, {}));
        if (i) timed.grid_eye.ms.push_back(context.timings().compute_ms);
        gpu::InterpolateStats between_stats;
        REPRISE_TRY(context.interpolate(before, previous_color, now, color, 0.5f, filled, eye_depth,
                                        between_stats));
        if (i) timed.between.ms.push_back(context.timings().compute_ms);
        REPRISE_TRY(context.interpolate(before, previous_color, now, color, 0.5f, filled, eye_depth,
                                        between_stats, {.grid = true}));
        if (i) timed.grid_between.ms.push_back(context.timings().compute_ms);
        REPRISE_TRY(context.interpolate(before, previous_color, now, color, 0.5f, filled, eye_depth,
                                        between_stats, kRefinedBetween));
        if (i)
            timed.refined_between.ms.push_back(context.timings().compute_ms +
                                               context.timings().cpu_ms);
        gpu::ExtrapolateStats ahead_stats;
        REPRISE_TRY(context.extrapolate(before, previous_color, current.camera.view,
                                        current.camera.projection, 1.0f, filled, eye_depth, out,
                                        ahead_stats, kExtrapolation));
        if (i) timed.ahead.ms.push_back(context.timings().compute_ms);
        REPRISE_TRY(context.extrapolate(before, previous_color, current.camera.view,
                                        current.camera.projection, 1.0f, filled, eye_depth, out,
                                        ahead_stats, kGridExtrapolation));
        if (i) timed.grid_ahead.ms.push_back(context.timings().compute_ms);
    }
    return {};
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
    StageTimes stages[11] = {
        {"reproject RGBA"},      {"pull-push (depth)"},    {"splat x-0.5"},
        {"stereo-eye splat+pp"}, {"interpolate splat+pp"}, {"extrapolate splat+pp"},
        {"upsample 1/4 Herzog"}, {"stereo-eye grid+pp"},   {"extrapolate grid+pp"},
        {"interpolate grid+pp"}, {"interpolate default"}};
    // Herzog upsampling of every other pixel of every other row (jitter -0.5 px: the low pixel
    // (u, v) is the full pixel (2u, 2v)), guided by the frame's full G-buffer, with history.
    warp::SpatioTemporalUpsampler cpu_upsampler;
    std::unique_ptr<gpu::Upsampler> gpu_upsampler;
    REPRISE_TRY(gpu::Upsampler::create(*context, {}, gpu_upsampler));
    Image<glm::vec4> low((w + 1) / 2, (h + 1) / 2), cpu_up(w, h), gpu_up(w, h);
    // The previous frame one period on, seen by the current camera.
    warp::PoseExtrapolator extrapolator(kExtrapolation), grid_extrapolator(kGridExtrapolation);
    Frame cpu_ahead, gpu_ahead;
    // The CPU's in-between frame with the same method (both sides splatted, blended, pull-push).
    const warp::FrucOptions between_options{
        .warp = warp::WarpMethod::Splat, .true_motion = false, .refine = {.enabled = false}};
    warp::FrameRateConverter converter, grid_converter, default_converter;
    REPRISE_TRY(warp::FrameRateConverter::create(2, between_options, converter));
    const warp::FrucOptions grid_between_options{.true_motion = false,
                                                 .refine = {.enabled = false}};
    REPRISE_TRY(warp::FrameRateConverter::create(2, grid_between_options, grid_converter));
    // The default: the grid, true motion, refinement (its flow on the CPU on both backends).
    REPRISE_TRY(warp::FrameRateConverter::create(2, {}, default_converter));
    Frame between_in, gpu_between;
    warp::SplatOptions splat_options;
    const stereo::StereoOptions eye_options{.warp = stereo::StereoWarp::Splat};
    Image<glm::vec4> cpu_color(w, h), gpu_color(w, h);
    Image<float> cpu_depth(w, h), gpu_depth(w, h);
    Image<uint8_t> cpu_covered(w, h), gpu_covered(w, h);
    stereo::StereoSynthesizer synthesizer;
    Frame cpu_eye, gpu_eye;
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

        // The current frame splatted halfway to the previous one (interpolation's half).
        Timing& cpu_splat = timing ? stages[2].cpu : scratch;
        const warp::WarpTarget cpu_target{
            cpu_color.view(), cpu_depth.view(), {}, cpu_covered.view()};
        const warp::WarpTarget gpu_target{
            gpu_color.view(), gpu_depth.view(), {}, gpu_covered.view()};
        time_once(cpu_splat, [&] { warp::splat(current, -0.5f, cpu_target, splat_options); });
        Timing splat_total;
        std::size_t covered = 0;
        time_once(splat_total, [&] {
            status = context->splat(current, -0.5f, gpu_target, splat_options, covered);
        });
        REPRISE_TRY(status);
        if (timing) record(stages[2], context->timings(), splat_total.ms[0]);
        stages[2].worst_db = std::min(stages[2].worst_db, display_psnr(cpu_color, gpu_color));

        // The right eye from the current frame as the left (IPD 64 mm).
        const Camera right = stereo::eye_cameras(current.camera, {}, stereo::Anchor::Left).right;
        Timing& cpu_eye_time = timing ? stages[3].cpu : scratch;
        time_once(cpu_eye_time,
                  [&] { synthesizer.synthesize(current, right, cpu_eye, eye_options); });
        Timing eye_total;
        stereo::StereoStats eye_stats;
        time_once(eye_total, [&] {
            status = context->stereo_eye(current, right, gpu_eye, eye_stats, eye_options);
        });
        REPRISE_TRY(status);
        if (timing) record(stages[3], context->timings(), eye_total.ms[0]);
        stages[3].worst_db =
            std::min(stages[3].worst_db, display_psnr(cpu_eye.color, gpu_eye.color));

        // The default eye: the grid (its cells grown on the GPU), pull-push.
        Timing& cpu_grid_eye = timing ? stages[7].cpu : scratch;
        time_once(cpu_grid_eye, [&] { synthesizer.synthesize(current, right, cpu_eye, {}); });
        Timing grid_eye_total;
        time_once(grid_eye_total,
                  [&] { status = context->stereo_eye(current, right, gpu_eye, eye_stats, {}); });
        REPRISE_TRY(status);
        if (timing) record(stages[7], context->timings(), grid_eye_total.ms[0]);
        stages[7].worst_db =
            std::min(stages[7].worst_db, display_psnr(cpu_eye.color, gpu_eye.color));

        // The frame halfway between the previous and the current one: the converter gets the
        // current frame (it holds the previous) and gives the made frame, then the input.
        auto between = [&](StageTimes& stage, warp::FrameRateConverter& cpu_converter,
                           const gpu::InterpolateOptions& gpu_options) {
            Timing& cpu_between = timing ? stage.cpu : scratch;
            between_in = current;
            Frame received[2];
            int count = 0;
            time_once(cpu_between, [&] {
                status = cpu_converter.send(std::move(between_in));
                while (count < 2 && cpu_converter.receive(received[count])) ++count;
            });
            REPRISE_TRY(status);
            Timing between_total;
            gpu::InterpolateStats between_stats;
            time_once(between_total, [&] {
                status = context->interpolate(previous, current, 0.5f, gpu_between, between_stats,
                                              gpu_options);
            });
            REPRISE_TRY(status);
            if (timing) record(stage, context->timings(), between_total.ms[0]);
            if (count == 2)
                stage.worst_db =
                    std::min(stage.worst_db, display_psnr(received[0].color, gpu_between.color));
            return Status{};
        };
        REPRISE_TRY(between(stages[4], converter, {}));
        REPRISE_TRY(between(stages[9], grid_converter,
                            {.grid = true, .grid_options = grid_between_options.grid}));
        REPRISE_TRY(between(stages[10], default_converter, kRefinedBetween));

        const Camera& to = current.camera;
        Timing& cpu_ahead_time = timing ? stages[5].cpu : scratch;
        time_once(cpu_ahead_time, [&] {
            status = extrapolator.extrapolate(previous, to.view, to.projection, 1.0f, cpu_ahead);
        });
        REPRISE_TRY(status);
        Timing ahead_total;
        gpu::ExtrapolateStats ahead_stats;
        time_once(ahead_total, [&] {
            status = context->extrapolate(previous, to.view, to.projection, 1.0f, gpu_ahead,
                                          ahead_stats, kExtrapolation);
        });
        REPRISE_TRY(status);
        if (timing) record(stages[5], context->timings(), ahead_total.ms[0]);
        stages[5].worst_db =
            std::min(stages[5].worst_db, display_psnr(cpu_ahead.color, gpu_ahead.color));

        // The default extrapolation: the grid (its cells grown on the GPU), pull-push.
        Timing& cpu_grid_ahead = timing ? stages[8].cpu : scratch;
        time_once(cpu_grid_ahead, [&] {
            status =
                grid_extrapolator.extrapolate(previous, to.view, to.projection, 1.0f, cpu_ahead);
        });
        REPRISE_TRY(status);
        Timing grid_ahead_total;
        time_once(grid_ahead_total, [&] {
            status = context->extrapolate(previous, to.view, to.projection, 1.0f, gpu_ahead,
                                          ahead_stats, kGridExtrapolation);
        });
        REPRISE_TRY(status);
        if (timing) record(stages[8], context->timings(), grid_ahead_total.ms[0]);
        stages[8].worst_db =
            std::min(stages[8].worst_db, display_psnr(cpu_ahead.color, gpu_ahead.color));

        for (int v = 0; v < low.height(); ++v)
            for (int u = 0; u < low.width(); ++u) low(u, v) = current.color(2 * u, 2 * v);
        const glm::vec2 jitter(-0.5f);
        Timing& cpu_up_time = timing ? stages[6].cpu : scratch;
        time_once(cpu_up_time,
                  [&] { cpu_upsampler.upsample(low.view(), jitter, current, cpu_up.view()); });
        Timing up_total;
        time_once(up_total, [&] {
            status = gpu_upsampler->upsample(low.view(), jitter, current, gpu_up.view());
        });
        REPRISE_TRY(status);
        if (timing) record(stages[6], gpu_upsampler->timings(), up_total.ms[0]);
        stages[6].worst_db = std::min(stages[6].worst_db, display_psnr(cpu_up, gpu_up));
    }
    REPRISE_TRY(time_texture_path(*context, frames.back(), frames[frames.size() - 2], cpu_hit,
                                  int(frames.size()) - 2,
                                  {stages[0].textures, stages[1].textures, stages[3].textures,
                                   stages[4].textures, stages[5].textures, stages[7].textures,
                                   stages[8].textures, stages[9].textures, stages[10].textures}));
    std::printf(
        "gles: %s; GPU columns are medians; gles cpu: the work left on the CPU (refinement's "
        "optical flow; for a skewed projection the grid's displacement and cells); textures: the "
        "texture entry point on textures already on the GPU (compute alone; with the flow for "
        "the default in-between frame)\n",
        context->description().c_str());
    std::printf("%-10s %-20s %9s %9s %9s %9s %9s %9s %9s %9s %9s %8s\n", "size", "stage",
                "cpu best", "cpu med", "gles cpu", "upload", "compute", "download", "gles med",
                "textures", "tex/cpu", "dB vs cpu");
    for (const StageTimes& s : stages)
        std::printf("%-10s %-20s %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f %9.3f %8.3fx %8.1f\n",
                    size.c_str(), s.name, s.cpu.best(), s.cpu.median(), s.prep.median(),
                    s.upload.median(), s.compute.median(), s.download.median(), s.total.median(),
                    s.textures.median(), s.textures.median() / s.cpu.median(), s.worst_db);
    return {};
}

}  // namespace reprise::cli
