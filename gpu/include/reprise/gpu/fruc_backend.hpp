#pragma once
// The GPU as the maker of warp::FrameRateConverter's in-between frames (`reprise fruc --backend
// gles`, Python's Converter(backend="gles")): the converter keeps order, cuts, still pairs,
// repair and UI on the CPU; each in-between frame is Context::interpolate.
#include <cstddef>

#include "reprise/gpu/context.hpp"
#include "reprise/warp/fruc.hpp"

namespace reprise::gpu {

class FrucBackend final : public warp::InterpolationBackend {
public:
    // `context` must outlive the backend.
    explicit FrucBackend(Context& context, const warp::SplatOptions& splat = {})
        : context_(context), splat_(splat) {}
    // Interpolation with warp splat (these splat options), fill pull-push, true motion and
    // refinement off: what Context::interpolate makes the CPU's frame for.
    static Status check(const warp::FrucOptions& options, const warp::SplatOptions& splat = {});
    Status supports(const warp::FrucOptions& options) const override {
        return check(options, splat_);
    }
    // Colour and depth; the made frame carries no motion.
    Status interpolate(const GBufferView& a, const GBufferView& b, float s, Frame& out,
                       warp::FrucCounters& counters) override;

    // The phases of every frame made so far, summed, and how many.
    const Timings& total() const { return total_; }
    std::size_t frames() const { return frames_; }

private:
    Context& context_;
    warp::SplatOptions splat_;
    Timings total_;
    std::size_t frames_ = 0;
};

}  // namespace reprise::gpu
