#pragma once
// The stages of frame-rate upconversion, shared by interpolate.cpp, extrapolate.cpp and fruc.cpp.
#include "reprise/core/gbuffer.hpp"
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
    WarpBuffers side_a;       // interpolation: frame a warped; extrapolation: the dynamic layer
    WarpBuffers side_b;       // interpolation: b's coverage (b is warped into the output)
    Image<float> layer_depth;        // extrapolation: the input's depth with some pixels left out
    Image<glm::vec2> layer_motion;   // and the static layer's displacement
    Image<uint8_t> valid;
    Image<glm::vec4> reprojected;
    GridWarper grid;
    PullPush pull_push;
    AndreevInpaint andreev;
};

// Warps `source` by `factor` times its motion into `out` with the chosen method; returns the
// number of covered pixels (the target's contract: colour 0, depth +inf, motion 0 elsewhere).
std::size_t warp_into(const GBufferView& source, float factor, const FrucOptions& options,
                      FrucScratch& scratch, const WarpTarget& out, FrucCounters& counters);

// Fills the holes of `color` (valid = 0; `holes` of them, counted by the caller) as options.fill
// says, using depth for the side to prefer; counts what it did or skipped.
void fill_holes(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                ImageView<const float> depth, std::size_t holes, const FrucOptions& options,
                FrucScratch& scratch, FrucCounters& counters);

// Frame at fraction s in (0, 1) between a (earlier) and b (later) into out (colour, depth, and
// motion times motion_scale). Without use_a (a's motion is not trustworthy, e.g. it starts a
// shot) only b is warped.
void interpolate_frame(const GBufferView& a, const GBufferView& b, float s, bool use_a,
                       float motion_scale, const FrucOptions& options, FrucScratch& scratch,
                       Frame& out, FrucCounters& counters);

// Frame s frame periods after f (Andreev: static layer by camera-only reprojection, holes
// filled from static neighbourhoods, dynamic objects drawn on top at extrapolated positions);
// its backward motion per input period times motion_scale.
void extrapolate_frame(const GBufferView& f, float s, float motion_scale, const FrucOptions& options,
                       FrucScratch& scratch, Frame& out, FrucCounters& counters);

// The same towards an explicit camera (view, projection): the static layer lands where that
// camera sees it, moving objects go s periods along their motion (constant screen velocity).
void extrapolate_to_camera(const GBufferView& f, const glm::mat4& future_view, const glm::mat4& future_projection,
                           float s, float motion_scale, const FrucOptions& options, FrucScratch& scratch,
                           Frame& out, FrucCounters& counters);

// True when every motion vector is exactly zero (and finite).
bool motion_is_zero(const GBufferView& f);

}  // namespace reprise::warp
