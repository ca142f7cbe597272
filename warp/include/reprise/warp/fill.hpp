#pragma once
// Hole filling for warped frames: pull-push (Marroquim et al. 2007), its depth-aware variant,
// Andreev-style patch inpainting and frequency-selective reconstruction.
//
// Shared rules: a pixel is a hole where valid(p) == 0 or where its RGB is not finite (NaN/Inf
// never spread). Only the RGB of holes is written; valid pixels and every alpha stay bit-exact.
// With `depth` (same size, linear depth as in Frame), where samples disagree in depth by more
// than kBackgroundDepthRatio the nearer ones are left out, so that disocclusions fill from the
// background rather than from the foreground edge; NaN depth counts as +inf, negative as 0.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "reprise/core/frame.hpp"

namespace reprise::warp {

inline constexpr float kBackgroundDepthRatio = 1.1f;

struct FillStats {
    std::size_t holes = 0;     // hole pixels found on entry (including non-finite colour)
    std::size_t unfilled = 0;  // holes left as they were (no valid pixel to fill from)
    int levels = 0;            // pyramid levels built (pull-push) or passes run (Andreev)
};

// Pull-push: the pull averages each 2x2 block of valid samples into a coarser level with a
// saturating weight min(1, sum) until a level has no empty pixel (at most down to 1x1); the push
// fills empty pixels from the bilinearly upsampled coarser level. With depth, a block keeps only
// the samples within the ratio of its farthest one, and the upsampling only such taps. With no
// valid pixel at all the image is left unchanged and holes == unfilled == W*H. `fill` is
// threaded and reuses its scratch pyramid (no allocation while the size stays the same);
// `fill_reference` is the plain scalar version it is tested against (same arithmetic, same
// result).
class PullPush {
public:
    FillStats fill(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                   ImageView<const float> depth = {});
    FillStats fill_reference(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                             ImageView<const float> depth = {});

private:
    std::vector<Image<glm::vec4>> color_levels_;  // levels 1.., rgb premultiplied, a = weight
    std::vector<Image<float>> depth_levels_;      // farthest kept depth per pixel
    Image<uint8_t> hole_bits_;                    // per level-1 pixel: which of its 2x2 are holes
};

// Andreev-style inpainting: each hole pixel looks left, right, up and down for the nearest valid
// pixel at distance k and copies the pixel mirrored about the hole's edge (distance k - 1 beyond
// that pixel, clamped to the run of valid pixels there); the directions found are averaged with
// weights 1/k. With depth, of two opposite directions whose sources differ by more than the
// ratio only the farther is used (comparing only opposite sides keeps a distant background seen
// along the other axis from overriding the adjacent one). Pixels filled in one pass are valid in
// the next; passes repeat until no hole is left, a pass fills nothing, or max_passes (then
// `unfilled` says how many are left, untouched). One pass fills every hole with a valid pixel in
// its row or column, so an image with any valid pixel is filled within two passes.
// Deterministic for any thread count; the scratch is kept while the size stays the same.
class AndreevInpaint {
public:
    FillStats fill(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                   ImageView<const float> depth = {}, int max_passes = 64);

private:
    Image<uint8_t> state_;       // 0 hole, 1 valid on entry, 2 filled by an earlier pass
    Image<uint16_t> up_, down_;  // holes: distance to the nearest valid pixel; valid: run length
    Image<float> filled_depth_;
};

// Frequency-selective reconstruction (Seiler et al. 2015; Genser et al. 2018: OpenCV contrib's
// xphoto::inpaint, FSR_FAST): each block with holes is modelled as a sparse sum of DCT basis
// functions fitted to its known pixels, which continues texture and edges into a hole that
// pull-push blurs. It works on 8-bit display values (sRGB of colour clamped to [0, 1]): filled
// pixels are at most 1 and quantised to display steps. With depth, a valid
// pixel within 8 px of a hole that is nearer than the farthest valid pixel within 8 px by the
// background ratio is not a known sample (it keeps its colour), so disocclusions continue the
// background. Holes are filled whenever any pixel is valid; with none, unfilled == holes.
// Single-threaded and far slower than the other fills (docs/benchmarks.md has its cost).
class PatchFill {
public:
    FillStats fill(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                   ImageView<const float> depth = {});

private:
    Image<uint8_t> known_, away_;  // 255: a known sample; away: no hole within 8 px
    Image<float> far_, farthest_;  // known depth (holes 0), its maximum within 8 px
    Image<glm::u8vec3> source_;    // display values, BGR
};

// One-shot form of AndreevInpaint::fill (allocates its scratch per call).
FillStats inpaint_andreev(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                          ImageView<const float> depth = {}, int max_passes = 64);

// Each row's holes between an image edge and the row's outermost valid pixel, up to `max_run`
// of them beside that pixel, take its colour and depth (when given) and become valid; rows
// without a valid pixel are left. What a camera uncovers at the border continues what is beside
// it, where a fill that prefers the farthest samples pulls the background across it. Returns
// how many pixels it made valid.
std::size_t continue_border_rows(ImageView<glm::vec4> color, ImageView<float> depth,
                                 ImageView<uint8_t> valid, int max_run);
// Made frames (interpolated and extrapolated) continue this many pixels of each row's border
// strip before their fill by default (FrucOptions::border_run; docs/benchmarks.md: all of a wider
// strip fills worse where it crosses textured ground or posts).
inline constexpr int kMadeFrameBorderRun = 8;

}  // namespace reprise::warp
