#pragma once
// Per-pixel displacement from the source's camera to another camera through depth (exact for
// static geometry): the warp field of a synthesized stereo eye.
#include <glm/vec2.hpp>

#include "reprise/core/gbuffer.hpp"

namespace reprise::warp {

// p + displacement is where pixel p of `source` lands in `target`; target_depth is its depth
// there (+inf for background). NaN where the depth is NaN or negative or the point lands behind
// the target camera. The size is the depth's.
void camera_displacement(const GBufferView& source, const Camera& target,
                         ImageView<glm::vec2> displacement, ImageView<float> target_depth);

}  // namespace reprise::warp
