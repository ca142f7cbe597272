#pragma once
// Forward reprojection: a frame scattered along its motion to another instant, z-buffered.
#include <cstddef>
#include <cstdint>

#include "reprise/core/frame.hpp"
#include "reprise/core/gbuffer.hpp"

namespace reprise::warp {

// The output of every forward warp: colour, depth and motion where covered, and coverage.
// The warp initialises all of it; where nothing landed: colour 0, depth +inf, motion 0, covered 0.
struct WarpTarget {
    ImageView<glm::vec4> color;
    ImageView<float> depth;       // z-buffer: nearer wins; +inf where nothing landed
    ImageView<glm::vec2> motion;  // the source's motion carried along (may be empty)
    // 1 where something landed; kCoveredStretched where only a shape stretched over a
    // disocclusion did (the grid warp's edge triangles)
    ImageView<uint8_t> covered;
};
inline constexpr uint8_t kCoveredStretched = 2;

struct SplatOptions {
    // 1: the pixel that contains the landing point; 2: the pixels whose centres lie less than one
    // pixel from it on both axes (up to 2x2; exactly one when it lands on a pixel centre).
    int footprint = 2;
    // Two candidates whose depths differ by less than this fraction are the same surface: the
    // one landing nearer the pixel centre wins. Otherwise the nearer depth wins. Remaining ties
    // go to the first in source order (row-major), so the result never depends on threading.
    float depth_tolerance = 0.01f;
};

// Moves pixel p of `source` to p + factor * motion(p), with `factor` in source-frame periods:
// interpolation towards the previous frame at fraction s uses factor = (1 - s) from frame n and
// factor = -s from frame n-1 (its motion negated: constant velocity); extrapolation by s
// frames uses factor = -s. Depth, colour and motion are carried unchanged. Background (+inf
// depth) is splatted too and loses against any geometry. Pixels with NaN/Inf motion, or NaN or
// negative depth, are dropped, and so is whatever lands off the target. Returns the number of
// covered pixels. The target may differ in size from the source (same pixel coordinates).
// Keeps a per-thread scratch (two ints per source row, eight target rows), grown on first use.
std::size_t splat(const GBufferView& source, float factor, const WarpTarget& target,
                  const SplatOptions& options = {});
std::size_t splat_reference(const GBufferView& source, float factor, const WarpTarget& target,
                            const SplatOptions& options = {});

}  // namespace reprise::warp
