#pragma once
// The stages of frame-rate upconversion, shared by interpolate.cpp, extrapolate.cpp and fruc.cpp.
#include <memory>
#include <vector>

#include "reprise/core/gbuffer.hpp"
#include "reprise/warp/fruc.hpp"
#include "reprise/warp/refine.hpp"
#include "reprise/warp/shot_change.hpp"

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
    WarpBuffers side_a;               // interpolation: frame a warped
    WarpBuffers side_b;               // interpolation: b's coverage (b is warped into the output)
    Image<float> layer_depth;         // extrapolation: the input's depth with some pixels left out
    Image<glm::vec2> layer_motion;    // and the static layer's displacement
    Image<glm::vec2> true_a, true_b;  // interpolation: motion that lands where the frame goes
    Image<glm::vec2> inverted;        // the later frame's moving pixels, at their earlier place
    Image<float> inverted_depth;
    Image<uint8_t> valid;
    // Inputs as the warps take them (warp_input): silhouettes widened, colour encoded.
    Image<float> wide_depth[2];
    Image<glm::vec2> wide_motion[2];
    Image<glm::vec4> encoded_color[2];
    uint64_t prepared_key[2] = {0, 0};  // the input each holds
    int prepared_as[2] = {0, 0};        // ... how: 1 widened, 2 encoded, 3 both
    // Set before a stage: which input is in slot 0 (a, or the one extrapolated) and slot 1 (b).
    // Equal non-zero keys mean the same frame, widened once however many frames it makes;
    // 0 = not known, widened every time. Keys are unique in the process (next_frame_key): a
    // backend shared by several converters or extrapolators keeps their uploads apart.
    uint64_t input_key[2] = {0, 0};
    ShotChangeScratch shot_change;
    GridWarper grid;
    PullPush pull_push;
    AndreevInpaint andreev;
    PatchFill patch;
    MotionRefiner refiner;
};

// Warps `source` by `factor` times its motion into `out` with the chosen method; returns the
// number of covered pixels (the target's contract: colour 0, depth +inf, motion 0 elsewhere).
std::size_t warp_into(const GBufferView& source, float factor, const FrucOptions& options,
                      FrucScratch& scratch, const WarpTarget& out, FrucCounters& counters);

// A frame key no other frame of this process has had (never 0).
uint64_t next_frame_key();

// `f` as the warps take it, in scratch slot `slot` (0 or 1): silhouettes widened and colour
// encoded (encodes_colour) when options ask for them; for options.backend, not widened for a
// backend that widens.
GBufferView warp_input(const GBufferView& f, int slot, const FrucOptions& options,
                       FrucScratch& scratch, FrucCounters& counters, bool for_backend = false);
// What options.backend is handed: warp_input's for it.
GBufferView backend_input(const GBufferView& f, int slot, const FrucOptions& options,
                          FrucScratch& scratch, FrucCounters& counters);

// Whether the warps take colour encoded (FrucOptions::perceptual, without a backend), and a made
// frame's colour back to linear light when they did.
bool encodes_colour(const FrucOptions& options);
void finish_colour(ImageView<glm::vec4> color, const FrucOptions& options);

// Fills the holes of `color` (valid = 0; `holes` of them, counted by the caller) as options.fill
// says, using depth for the side to prefer, after each row's border strip is continued (up to
// options.border_run px: those pixels become valid, with their depth); counts what it did or
// skipped.
void fill_holes(ImageView<glm::vec4> color, ImageView<uint8_t> valid, ImageView<float> depth,
                std::size_t holes, const FrucOptions& options, FrucScratch& scratch,
                FrucCounters& counters);

// Frame at fraction s in (0, 1) between a (earlier) and b (later) into out (colour, depth, and
// motion times motion_scale). Without use_a (a's motion is not trustworthy, e.g. it starts a
// shot) only b is warped.
void interpolate_frame(const GBufferView& a, const GBufferView& b, float s, bool use_a,
                       float motion_scale, const FrucOptions& options, FrucScratch& scratch,
                       Frame& out, FrucCounters& counters);

// Frame s frame periods after f: static pixels (camera-only motion, Andreev's test) where the
// camera s periods on sees them, moving ones s periods along their motion, in one warp, holes
// filled; its backward motion per input period times motion_scale. Made by options.backend when
// one is set (its error returned).
Status extrapolate_frame(const GBufferView& f, float s, float motion_scale,
                         const FrucOptions& options, FrucScratch& scratch, Frame& out,
                         FrucCounters& counters);

// The static-layer test of f against its own previous camera: static pixels (the camera alone
// explains their motion within `tolerance` px) keep their depth in depth_out and get their
// displacement to the camera (to_view, to_projection) in motion_out; the others NaN in both.
// Returns the number of others.
std::size_t static_layer(const GBufferView& f, const glm::mat4& to_view,
                         const glm::mat4& to_projection, float tolerance,
                         ImageView<float> depth_out, ImageView<glm::vec2> motion_out);

// The motion m for which p + factor * m is where pixel p of `f` is seen by camera `to`: exact
// for what f's camera explains (static pixels, from depth and both cameras); elsewhere the
// `inverted` motion where it is finite (may be empty), else f's own. Returns the moving pixels.
std::size_t motion_toward(const GBufferView& f, const Camera& to, float factor,
                          ImageView<const glm::vec2> inverted, float tolerance,
                          Image<float>& static_depth, ImageView<glm::vec2> out);

// The later frame's moving pixels splatted to where they were in the earlier frame, carrying
// their backward motion (nearest wins; NaN where none lands): the earlier frame's true forward
// motion is its negation. Without a camera on b every pixel counts as moving.
void invert_motion(const GBufferView& b, float tolerance, Image<float>& static_depth,
                   Image<glm::vec2>& inverted, Image<float>& depth);

// The same towards an explicit camera (view, projection): static pixels land where that camera
// sees them, moving ones go s periods along their motion (constant screen velocity). A frame
// without a projection goes along its motion alone (view and projection unused).
Status extrapolate_to_camera(const GBufferView& f, const glm::mat4& future_view,
                             const glm::mat4& future_projection, float s, float motion_scale,
                             const FrucOptions& options, FrucScratch& scratch, Frame& out,
                             FrucCounters& counters);

}  // namespace reprise::warp
