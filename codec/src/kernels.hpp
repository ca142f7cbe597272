#pragma once
// Row kernels with a SIMD version chosen at run time (simd_kernels.cpp, Highway) beside their
// scalar reference (in the stage's own file). Each SIMD version gives its reference's bits: the
// codec's encoder and decoder must agree whatever level either runs at.
#include <cstddef>
#include <cstdint>

#include <glm/ext/vector_uint4_sized.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

namespace reprise::codec {

// Inter prediction of one row of a plane: pixel x fetched from the reference plane at
// x + motion with the Catmull-Rom filter (1/64 pel, integer), clamped to [lo, hi] (whole-pixel
// positions copy the reference as it is). Luma takes motion0[min(x, motion_width - 1)]; 4:2:0
// chroma the mean of the 2x2 luma motions (motion0 row 2y, motion1 row 2y + 1) in chroma pixels.
// Non-finite motion counts as 0.
struct PredictRow {
    const int16_t* reference;
    int width, height;  // of the plane (and of out)
    int y;
    const glm::vec2* motion0;
    const glm::vec2* motion1;  // chroma only
    int motion_width;
    bool subsampled;
    int lo, hi;
    int16_t* out;
};
// The reference does pixels [x_begin, x_end).
void predict_row_reference(const PredictRow& row, int x_begin, int x_end);
void predict_row(const PredictRow& row);

// Catmull-Rom weights per 1/64 phase, in 1/128, summing to 128 ([phase][tap]).
const int32_t (&catmull_rom_weights())[64][4];
// The same, one word per phase: tap i's weight + kPackedWeightBias in byte i (weights lie in
// -9..128), so that one gather fetches a lane's four taps.
inline constexpr int32_t kPackedWeightBias = 16;
const uint32_t (&catmull_rom_packed())[64];
// The same as pairs of 16-bit weights, taps 0 and 1 (low, high) and taps 2 and 3, for a pairwise
// multiply-add.
const uint32_t (&catmull_rom_pairs())[2][64];

// The encoder's skip and intra tests (color_coder.cpp): for each of `blocks` 8x8 blocks side by
// side, from `source` and `prediction` (their top-left pixels; rows `stride` apart), the sum and
// the largest of |source - prediction| (values within -255..255).
struct BlockDifferencesRow {
    const int16_t* source;
    const int16_t* prediction;
    int stride, blocks;
    int32_t* sum;
    int32_t* largest;
};
// The reference does blocks [b_begin, b_end).
void block_differences_row_reference(const BlockDifferencesRow& row, int b_begin, int b_end);
void block_differences_row(const BlockDifferencesRow& row);

// Revealed luma pixels of one row (predict.cpp): a pixel whose landing floor(p + 0.5 + m) lies
// inside the picture (never with NaN or infinite motion) and whose reference depth there is more
// than 4 % off its own, either way (NaN compares false: not revealed).
struct RevealRow {
    const float* depth;            // the row's decoded depth
    const glm::vec2* motion;       // the row's motion to the reference
    const float* reference_depth;  // the reference's whole depth picture, width x height
    int width, height, y;
    int reference_stride;  // of reference_depth's rows, in floats
    uint8_t* out;          // 1: revealed, 0: not
};
// Both return how many of their pixels are revealed.
std::size_t reveal_row_reference(const RevealRow& row, int x_begin, int x_end);
std::size_t reveal_row(const RevealRow& row);

// Camera motion of one row (geometry.cpp, camera_motion): under perspective a pixel's clip
// position in the other camera is (a0 + x a1) + z (b0 + x b1) for finite depth z >= 0; other
// pixels (background, negative or NaN depth, orthographic) unproject through `projection` and
// go through `to_clip`. Out: the motion to the other camera's pixel, NaN where the point is
// behind it or has no depth.
struct CameraMotionRow {
    glm::vec4 a0, a1, b0, b1;
    glm::mat4 projection, to_clip;
    bool perspective;
    float far_plane;
    int y, width, height;
    const float* depth;
    glm::vec2* out;
};
void camera_motion_row_reference(const CameraMotionRow& row, int x_begin, int x_end);
void camera_motion_row(const CameraMotionRow& row);

// Colour conversion of one row into YCoCg-R: linear RGB -> 8-bit sRGB codes (color.cpp's
// table and thresholds) -> y, co, cg; or the codes themselves, given as `display` (RGBA8, alpha
// not read) instead of `color`.
struct ToPlanesRow {
    const glm::vec4* color;
    int width;
    const glm::u8vec4* display = nullptr;
    int16_t* y;
    int16_t* co;
    int16_t* cg;
};
void to_planes_row_reference(const ToPlanesRow& row, int x_begin, int x_end);
void to_planes_row(const ToPlanesRow& row);
// The 8-bit code's table: start[i] is the code of i / kSrgbSteps, thresholds[k] the linear
// value where code k + 1 begins. No step holds two thresholds (the steepest codes, at 0, are
// 1 / (255 * 12.92) apart, more than a step), so a value's code is start[i], plus one from
// start_threshold[i] = thresholds[start[i]] on.
inline constexpr int kSrgbSteps = 4096;
struct SrgbTables {
    int32_t start[kSrgbSteps + 1];
    float start_threshold[kSrgbSteps + 1];
    float thresholds[256];  // [255] = +inf
    float to_linear[256];
};
const SrgbTables& srgb_tables();

// One row of YCoCg-R (chroma at full resolution) -> linear RGB; alpha 0 where the depth is
// not finite (no depth: 1). Or the 8-bit sRGB codes, to `display` (RGBA8, alpha 0 or 255) instead
// of `out`.
struct FromPlanesRow {
    const int16_t* y;
    const int16_t* co;
    const int16_t* cg;
    const float* depth;  // null without depth
    int width;
    glm::vec4* out;
    glm::u8vec4* display = nullptr;
};
void from_planes_row_reference(const FromPlanesRow& row, int x_begin, int x_end);
void from_planes_row(const FromPlanesRow& row);

// Forward projection of `count` pixels from (x0, y) into another camera (reproject_depth): where
// pixel x0 + i lands (slot[i]: row-major pixel index, -1 for nowhere), its depth there (z[i]),
// the point it lands on (px[i], py[i], in pixels) and, where `inverse` is given, 1 / z[i]; those
// four are set only where it lands. Depth +inf, NaN or below 0 lands nowhere. Perspective or not,
// through `projection`.
struct ForwardRow {
    glm::mat4 projection, to_clip, to_camera;
    int x0, y, count, width, height;
    const float* depth;  // from x0
    int32_t* slot;
    float* z;
    float* px;
    float* py;
    float* inverse = nullptr;
};
// The reference does pixels [i_begin, i_end) of the row.
void forward_row_reference(const ForwardRow& row, int i_begin, int i_end);
void forward_row(const ForwardRow& row);

// The plane fit of reproject_depth: the depth each landed pixel of reference row y takes at the
// centre of the target pixel it lands in (int px, int py), on the plane in (px, py, 1/z) through
// its landing and those of a horizontal and a vertical neighbour on its surface (landed, same
// object, 1/z within max(kSameSurface of its own, k step)) k pixels away, k = span, span / 2, ...
// 1; the value is the mean of the plane's value through it and through each adjacent landing on the
// surface. Its own z where no k has both neighbours, the plane is degenerate or moves the value
// beyond the neighbours'. Inputs are whole width x height images (row-major); out is row y, written
// where the pixel landed (slot >= 0). Two landings d pixels apart are one surface when their
// inverse depths differ by at most this share of the larger, or by d view steps (a far surface seen
// at a grazing angle changes by more than a share per pixel). A post standing on the ground meets
// it within a few per cent: with 1/8, the version-13 share, the fit bridged such silhouettes.
inline constexpr float kSameSurface = 1.0f / 32;
struct PlaneRow {
    const int32_t* slot;   // the target pixel a landing went to, -1: none
    const int* object;     // the object it moved with, -1: none
    const float* inverse;  // 1 / z of each landing
    const float* z;
    const float* px;
    const float* py;
    int width, height, span, y;
    float step;  // 1/z per pixel of distance that counts as one surface (the view step)
    float* out;
};
void plane_row_reference(const PlaneRow& row, int x_begin, int x_end);
void plane_row(const PlaneRow& row);

// Whether any pixel of a row needs a motion residual (motion.cpp): the renderer's motion differs
// from the camera motion by 1/16 pixel or more, or exactly one of them is not finite.
struct MotionResidualRow {
    const glm::vec2* source;
    const glm::vec2* base;
    int width;
};
bool motion_residual_row_reference(const MotionResidualRow& row, int x_begin, int x_end);
bool motion_residual_row(const MotionResidualRow& row);

// Whether every pixel of a row keeps the decoded motion within `bound` px of the renderer's
// (motion_models.cpp, motion models' test): both finite and |decoded - source|^2 <= bound^2 in
// float, or else NaN in both x components.
struct MotionWithinRow {
    const glm::vec2* source;
    const glm::vec2* decoded;
    int width;
    float bound;
};
bool motion_within_row_reference(const MotionWithinRow& row, int x_begin, int x_end);
bool motion_within_row(const MotionWithinRow& row);

// An object's pixels in a run of one row (object_motion.cpp, fit_object_motions): how many are
// usable (depth finite and > 0, motion finite) and how many of those the camera motion `base`
// does not explain (|base - motion|^2 > bound^2 in float, or not finite).
struct ObjectPixelsRow {
    const float* depth;
    const glm::vec2* motion;
    const glm::vec2* base;
    int count;
    float bound;
};
struct ObjectPixels {
    int usable = 0, unexplained = 0;
};
ObjectPixels object_pixels_row_reference(const ObjectPixelsRow& row, int i_begin, int i_end);
ObjectPixels object_pixels_row(const ObjectPixelsRow& row);

// View-mode depth (depth.cpp, choose_view_code): whether each pixel keeps its temporal prediction,
// that is, the prediction exists (not kNoPrediction), the depth to code is finite and positive,
// and the prediction's inverse depth w_c (c step, or step / 2 for c = 0) is within the bound of
// w = 1 / z: |w_c - w| <= share kViewCodesPerStep step near^2, near = max(0, 1 - displacement
// max(w, w_c)), share the pixel's multiple of the bound (1 without `share`). In binary64.
struct ViewKeepRow {
    const float* source;       // the depth to code
    const uint32_t* temporal;  // the temporal prediction's codes
    int count;
    double step;  // 1/z per code
    double displacement;
    uint8_t* keep;                 // 1: the code is the prediction
    const float* share = nullptr;  // per pixel, or null
};
void view_keep_row_reference(const ViewKeepRow& row, int i_begin, int i_end);
void view_keep_row(const ViewKeepRow& row);
inline constexpr uint32_t kNoPrediction = 0xFFFFFFFFu;    // no depth code maps here
inline constexpr int kViewCodesPerStep = 32;              // view-mode codes per step q of 1/z
inline constexpr uint32_t kMaxViewCode = 1u << 30;        // view codes of surfaces: 0..2^30
inline constexpr uint32_t kInfCode = (1u << 30) + 1;      // background (+inf)
inline constexpr uint32_t kInvalidCode = (1u << 30) + 2;  // NaN, zero or negative depth

// Inter-frame depth (depth.cpp, reprojection_class): what the temporal prediction shows at each
// pixel of a row of a block row, raised into `out` (each byte the larger of the two): 2 where
// nothing landed (kNoPrediction), else 1 where the code differs by more than `step` from the one
// to its left (not at a block's first column, x % 8 == 0) or from the one above (`above`, null on
// the block row's first row), else 0.
struct ShowsRow {
    const uint32_t* temporal;
    const uint32_t* above;
    int count;
    uint32_t step;
    uint8_t* out;
};
void shows_row_reference(const ShowsRow& row, int i_begin, int i_end);
void shows_row(const ShowsRow& row);

// View-mode codes of one row of the reprojected reference's depth (depth.cpp, temporal_codes):
// NaN (nothing landed) kNoPrediction, +inf kInfCode, other depth that is not finite and
// positive kInvalidCode, else min(k, 2^30) with k = 1 / z / step rounded half to even, in
// binary64.
struct ViewCodeRow {
    const float* depth;
    int count;
    double step;  // 1/z per code
    uint32_t* out;
};
void view_code_row_reference(const ViewCodeRow& row, int i_begin, int i_end);
void view_code_row(const ViewCodeRow& row);

// The depth of view-mode codes (depth.cpp, depth_from_codes): float(1 / (c step)) in binary64
// (c = 0: 1 / (step / 2)) for c <= 2^30, +inf for kInfCode, NaN for any other code.
struct ViewDepthRow {
    const uint32_t* codes;
    int count;
    double step;
    float* out;
};
void view_depth_row_reference(const ViewDepthRow& row, int i_begin, int i_end);
void view_depth_row(const ViewDepthRow& row);

}  // namespace reprise::codec
