#include "reprise/gpu/fruc_backend.hpp"

#include <string>

namespace reprise::gpu {

Status FrucBackend::check(const warp::FrucOptions& o, const warp::SplatOptions& splat) {
    std::string unsupported;
    auto need = [&](bool ok, const char* what) {
        if (!ok) unsupported += std::string(unsupported.empty() ? "" : ", ") + what;
    };
    need(o.mode == warp::FrucMode::Interpolate, "mode interpolate");
    need(o.warp == warp::WarpMethod::Splat, "warp splat");
    need(o.fill == warp::FillMethod::PullPush, "fill pullpush");
    need(!o.true_motion, "true motion off");
    need(!o.refine.enabled, "refine off");
    need(o.splat.footprint == splat.footprint && o.splat.depth_tolerance == splat.depth_tolerance,
         "the backend's splat options");
    if (unsupported.empty()) return {};
    return Status::error("gpu: the GPU makes in-between frames with " + unsupported +
                         " only (docs/gpu.md)");
}

Status FrucBackend::interpolate(const GBufferView& a, const GBufferView& b, float s, Frame& out,
                                warp::FrucCounters& counters) {
    InterpolateStats stats;
    REPRISE_TRY(context_.interpolate(a, b, s, out, stats, splat_));
    const Timings& t = context_.timings();
    total_.upload_ms += t.upload_ms;
    total_.compute_ms += t.compute_ms;
    total_.download_ms += t.download_ms;
    ++frames_;
    counters.hole_pixels += stats.holes;
    counters.fills += stats.holes > 0;
    counters.fills_skipped += stats.holes == 0;
    return {};
}

}  // namespace reprise::gpu
