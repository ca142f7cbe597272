#pragma once
// Extrapolation of one frame to any camera (latency hiding, as ASW and Outatime): the static
// scene is reprojected with depth to the new camera, moving objects are carried `periods` frame
// periods further along their motion, holes are filled.
#include <cstdint>
#include <memory>

#include "reprise/warp/fruc.hpp"

namespace reprise::warp {

// Where extrapolation moves each pixel of `f` (with a projection): a static pixel (its camera
// alone explains its motion within `static_tolerance` px) to where (view, projection) sees it, the
// others `periods` along their own motion, as `displacement` in pixels (NaN: invalid);
// `layer_depth` is scratch of f's size. Returns how many pixels moved on their own. The grid or
// splat of `f` with this as its motion, by 1, is the extrapolated frame before its fill.
std::size_t extrapolation_displacement(const GBufferView& f, const glm::mat4& view,
                                       const glm::mat4& projection, float periods,
                                       float static_tolerance, ImageView<float> layer_depth,
                                       ImageView<glm::vec2> displacement);

class PoseExtrapolator {
public:
    explicit PoseExtrapolator(const FrucOptions& options = {.mode = FrucMode::Extrapolate});
    ~PoseExtrapolator();
    PoseExtrapolator(PoseExtrapolator&&) noexcept;
    PoseExtrapolator& operator=(PoseExtrapolator&&) noexcept;

    // `out` gets colour, depth and motion of `frame` as seen by (view, projection) `periods`
    // frame periods after it (periods >= 0; its motion is per period); a frame without a
    // projection goes along its motion alone. Scratch is sized once.
    // A non-zero `frame_key`, the same for the same frame, lets the work that depends on the
    // frame alone (its widened silhouettes, its colour encoded for FrucOptions::perceptual) be
    // done once for all the instants made from it.
    // With FrucOptions::backend the backend makes it; its error is returned (counters unchanged).
    Status extrapolate(const GBufferView& frame, const glm::mat4& view, const glm::mat4& projection,
                       float periods, Frame& out, uint64_t frame_key = 0);
    const FrucCounters& counters() const;

private:
    struct State;
    std::unique_ptr<State> state_;
};

}  // namespace reprise::warp
