#pragma once
// The stages of frame-rate upconversion, shared by interpolate.cpp, extrapolate.cpp and fruc.cpp.
#include "reprise/warp/fruc.hpp"

namespace reprise::warp {

// A warp's output images, sized once per frame size.
struct WarpBuffers {
    Image<glm::vec4> color;
    Image<float> depth;
    Image<glm::vec2> motion;
    Image<uint8_t> covered;

    void resize(int w, int h);
    WarpTarget target() { return {color.view(), depth.view(), motion.view(), covered.view()}; }
};

// Scratch for one converter: every per-frame buffer lives here.
struct FrucScratch {
    WarpBuffers side_a, side_b;
    Frame layer;                   // a copy of an input with some pixels invalidated
    Image<uint8_t> valid;
    Image<glm::vec4> reprojected;
    GridWarper grid;
    PullPush pull_push;
    AndreevInpaint andreev;
};

// Warps `source` by `factor` times its motion into `out` with the chosen method.
void warp_frame(const Frame& source, float factor, const FrucOptions& options, FrucScratch& scratch,
                WarpBuffers& out, FrucCounters& counters);

// Fills the holes of `color` (valid = 0) as options.fill says, using depth for the side to
// prefer; counts what it did or skipped.
void fill_holes(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                ImageView<const float> depth, const FrucOptions& options, FrucScratch& scratch,
                FrucCounters& counters);

// Frame at fraction s in (0, 1) between a (earlier) and b (later) into out (colour, depth, motion).
// Without use_a (a's motion is not trustworthy, e.g. it starts a shot) only b is warped.
void interpolate_frame(const Frame& a, const Frame& b, float s, bool use_a, const FrucOptions& options,
                       FrucScratch& scratch, Frame& out, FrucCounters& counters);

// Frame s frame periods after f (Andreev: static layer by camera-only reprojection, holes
// filled from static neighbourhoods, dynamic objects drawn on top at extrapolated positions).
void extrapolate_frame(const Frame& f, float s, const FrucOptions& options, FrucScratch& scratch,
                       Frame& out, FrucCounters& counters);

// True when every motion vector is exactly zero (and finite).
bool motion_is_zero(const Frame& f);

}  // namespace reprise::warp
