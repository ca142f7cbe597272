#pragma once
// The GPU as the maker of warp::FrameRateConverter's and warp::PoseExtrapolator's frames
// (`reprise fruc --backend gles`, `reprise connect --backend gles`, Python's
// Converter(backend="gles")): the caller keeps order, cuts, still pairs, repair and UI on the
// CPU; each in-between frame is Context::interpolate, each extrapolated one Context::extrapolate.
#include <cstddef>
#include <cstdint>

#include "reprise/gpu/context.hpp"
#include "reprise/gpu/upsampler.hpp"
#include "reprise/warp/fruc.hpp"

namespace reprise::gpu {

class FrucBackend final : public warp::WarpBackend {
public:
    // `context` must outlive the backend.
    explicit FrucBackend(Context& context, const warp::SplatOptions& splat = {})
        : context_(context), splat_(splat) {}
    // Warp grid, reverse or splat with these splat options; interpolation with fill pull-push
    // (refinement on or off), extrapolation with fill pull-push or none: what the GPU makes the
    // CPU's frames for.
    static Status check(const warp::FrucOptions& options, const warp::SplatOptions& splat = {});
    Status supports(const warp::FrucOptions& options) const override {
        return check(options, splat_);
    }
    // On the GPU, once per upload (FrucCounters::silhouette_pixels counted there, once per key).
    bool widens_silhouettes() const override { return true; }
    void silhouettes_counted(uint64_t frame_key) override { remember_counted(frame_key); }
    // Colour, depth and motion, as the CPU's.
    Status interpolate(const GBufferView& a, const GBufferView& b, float s, float motion_scale,
                       const warp::FrucOptions& options, Frame& out, warp::FrucCounters& counters,
                       uint64_t a_key, uint64_t b_key) override;
    Status extrapolate(const GBufferView& f, const glm::mat4& view, const glm::mat4& projection,
                       float periods, float motion_scale, const warp::FrucOptions& options,
                       Frame& out, warp::FrucCounters& counters, uint64_t frame_key) override;

    // Extrapolated frames left on the GPU for a display that draws them: `out` of extrapolate
    // gets no colour, depth or motion (emptied) and made() names the textures that hold them,
    // until the next call. Off by default (every frame downloaded).
    void keep_extrapolated_on_gpu(bool keep) { keep_on_gpu_ = keep; }
    // Extrapolated frames take what `upsampler` holds of them on the GPU (Upsampler::on_gpu: the
    // colour it kept, Upsampler::keep_output, and the depth and motion that guided it), nothing
    // of that uploaded; null: none. Not owned; an error on another context.
    Status inputs_from(const Upsampler* upsampler) {
        if (upsampler && &upsampler->context() != &context_)
            return Status::error("gpu fruc backend: the upsampler works on another GPU context");
        inputs_from_ = upsampler;
        return {};
    }
    MadeTextures made() const { return context_.made(); }

    // The phases of every frame made so far (interpolated or extrapolated), summed, and how many.
    const Timings& total() const { return total_; }
    std::size_t frames() const { return frames_; }
    // Frames made from inputs already uploaded for an earlier frame (same key), counted per input:
    // an extrapolated frame adds up to 1, an in-between frame up to 2.
    std::size_t uploads_kept() const { return uploads_kept_; }

private:
    // Adds the last call's timings and what its frame took.
    void count(std::size_t holes, bool filled, warp::FrucCounters& counters);
    // Adds an input's widened pixels once per frame key (an input both interpolated and
    // extrapolated is uploaded, and widened, by each), as the CPU counts them once per input.
    void count_silhouettes(uint64_t key, std::size_t pixels, warp::FrucCounters& counters);
    // Whether `key` was counted lately; remembers it either way (0: never counted).
    bool remember_counted(uint64_t key);
    Context& context_;
    warp::SplatOptions splat_;
    Timings total_;
    std::size_t frames_ = 0, uploads_kept_ = 0;
    bool keep_on_gpu_ = false;
    const Upsampler* inputs_from_ = nullptr;
    uint64_t counted_keys_[4] = {0, 0, 0, 0};  // the inputs whose widened pixels were counted last
};

}  // namespace reprise::gpu
