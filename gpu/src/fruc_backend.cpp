#include "reprise/gpu/fruc_backend.hpp"

#include <algorithm>
#include <iterator>
#include <string>

#include "reprise/core/camera_math.hpp"

namespace reprise::gpu {

Status FrucBackend::check(const warp::FrucOptions& o, const warp::SplatOptions& splat) {
    std::string unsupported;
    auto need = [&](bool ok, const char* what) {
        if (!ok) unsupported += std::string(unsupported.empty() ? "" : ", ") + what;
    };
    const bool extrapolate = o.mode != warp::FrucMode::Interpolate;
    need(o.warp == warp::WarpMethod::Splat || o.warp == warp::WarpMethod::Reverse ||
             o.warp == warp::WarpMethod::Grid,
         "warp grid, splat or reverse");
    if (!extrapolate) {
        need(o.fill == warp::FillMethod::PullPush, "fill pullpush");
    } else {
        need(o.fill == warp::FillMethod::PullPush || o.fill == warp::FillMethod::None,
             "fill pullpush or none");
    }
    need(o.warp != warp::WarpMethod::Splat || (o.splat.footprint == splat.footprint &&
                                               o.splat.depth_tolerance == splat.depth_tolerance),
         "the backend's splat options");
    if (unsupported.empty()) return {};
    return Status::error(std::string("gpu: the GPU makes ") +
                         (o.mode == warp::FrucMode::Interpolate ? "in-between" : "extrapolated") +
                         " frames with " + unsupported + " only (docs/gpu.md)");
}

Status FrucBackend::interpolate(const GBufferView& a, const GBufferView& b, float s,
                                float motion_scale, const warp::FrucOptions& options, Frame& out,
                                warp::FrucCounters& counters, uint64_t a_key, uint64_t b_key) {
    InterpolateStats stats;
    REPRISE_TRY(context_.interpolate(a, b, s, out, stats,
                                     {.splat = splat_,
                                      .reverse = options.warp == warp::WarpMethod::Reverse,
                                      .grid = options.warp == warp::WarpMethod::Grid,
                                      .grid_options = options.grid,
                                      .true_motion = options.true_motion,
                                      .static_tolerance = options.static_tolerance,
                                      .motion_scale = motion_scale,
                                      .refine = options.refine,
                                      .border_run = options.border_run,
                                      .widen_silhouettes = options.widen_silhouettes},
                                     a_key, b_key));
    uploads_kept_ += stats.uploads_kept;
    count_silhouettes(a_key, stats.silhouette_a, counters);
    count_silhouettes(b_key, stats.silhouette_b, counters);
    counters.border_pixels += stats.border;
    counters.grid_cells += stats.grid_cells;
    if (options.refine.enabled) {
        ++(stats.refine_skipped ? counters.refine_skipped : counters.refined_frames);
        counters.refine_tiles += stats.refine_tiles;
        counters.refine_tiles_left_out += stats.refine_tiles_left_out;
        counters.flow_pixels += stats.flow_pixels;
        counters.refined_pixels += stats.refined_pixels;
        counters.refine_ms += stats.refine_ms;
    }
    counters.true_motion += stats.true_motion;
    counters.linear_motion += stats.linear_motion;
    count(stats.holes, stats.holes > 0, counters);
    return {};
}

Status FrucBackend::extrapolate(const GBufferView& f, const glm::mat4& view,
                                const glm::mat4& projection, float periods, float motion_scale,
                                const warp::FrucOptions& options, Frame& out,
                                warp::FrucCounters& counters, uint64_t frame_key) {
    ExtrapolateStats stats;
    const FrameOnGpu on_gpu = inputs_from_ ? inputs_from_->on_gpu(f) : FrameOnGpu{};
    if (keep_on_gpu_) {
        REPRISE_TRY(context_.extrapolate_on_gpu(f, view, projection, periods, stats, options,
                                                motion_scale, frame_key, on_gpu));
        out.color.clear(), out.depth.clear(), out.motion.clear(), out.normal.clear();
        out.id.clear();
    } else {
        REPRISE_TRY(context_.extrapolate(f, view, projection, periods, out, stats, options,
                                         motion_scale, frame_key, on_gpu));
    }
    uploads_kept_ += stats.upload_kept;
    count_silhouettes(frame_key, stats.silhouette_pixels, counters);
    counters.border_pixels += stats.border;
    counters.grid_cells += stats.grid_cells;
    if (has_projection(f.camera))
        ++(stats.moving ? counters.dynamic_layers : counters.dynamic_skipped);
    count(stats.holes, stats.holes > 0 && options.fill != warp::FillMethod::None, counters);
    return {};
}

bool FrucBackend::remember_counted(uint64_t key) {
    if (key == 0) return false;
    if (std::find(std::begin(counted_keys_), std::end(counted_keys_), key) !=
        std::end(counted_keys_))
        return true;
    std::rotate(std::begin(counted_keys_), std::end(counted_keys_) - 1, std::end(counted_keys_));
    counted_keys_[0] = key;
    return false;
}

void FrucBackend::count_silhouettes(uint64_t key, std::size_t pixels,
                                    warp::FrucCounters& counters) {
    if (!remember_counted(key)) counters.silhouette_pixels += pixels;
}

void FrucBackend::count(std::size_t holes, bool filled, warp::FrucCounters& counters) {
    const Timings& t = context_.timings();
    total_.cpu_ms += t.cpu_ms;
    total_.upload_ms += t.upload_ms;
    total_.compute_ms += t.compute_ms;
    total_.download_ms += t.download_ms;
    ++frames_;
    counters.hole_pixels += holes;
    counters.fills += filled;
    counters.fills_skipped += holes == 0;
}

}  // namespace reprise::gpu
