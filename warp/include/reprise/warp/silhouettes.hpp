#pragma once
// Edge pixels with the nearer surface. A renderer's edge pixel blends the colours of the surfaces
// it straddles while its depth and motion are its centre's (docs/conventions.md); warped with
// the farther surface, that blended colour leaves a ghost contour where the silhouette was.
#include <cstddef>

#include "reprise/core/gbuffer.hpp"

namespace reprise::warp {

// A neighbour nearer than this fraction of a pixel's depth gives it its surface.
inline constexpr float kSilhouetteKeep = 1.0f - 0.15f;

// `f` with its depth and motion replaced by `depth` and `motion` (sized here): a pixel with a
// 4-neighbour nearer by more than 15 % of its own depth (background: any geometry; the in-between
// frame's one-surface tolerance) takes the depth and motion of the nearest such neighbour, so a
// silhouette is one pixel wider. NaN, negative and zero depths neither take nor give. Without
// depth `f` is returned as is; without motion only its depth is widened (`motion` untouched).
// `changed` (optional) gets the number of pixels that took a neighbour's.
//
// Measured on the built-in renderer's anti-aliased frames (smooth backgrounds): +0.4 to +2.2 dB
// in-between, up to +3.9 extrapolated, +0.4 to +4.4 in the second eye; on path-traced Blender
// renders -0.5 to +0.2 in-between. Over per-pixel noise a widened pixel that held no nearer
// colour costs more than the blended ones gain (docs/benchmarks.md).
GBufferView widen_silhouettes(const GBufferView& f, Image<float>& depth, Image<glm::vec2>& motion,
                              std::size_t* changed = nullptr);

// The depth and motion widen_silhouettes gives pixel (x, y) of `f` (which has both), alone.
void widened_pixel(const GBufferView& f, int x, int y, float& depth, glm::vec2& motion);

}  // namespace reprise::warp
