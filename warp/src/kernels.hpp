#pragma once
// Row kernels with a SIMD version chosen at run time (simd_kernels.cpp, Highway) beside their
// scalar reference (in the stage's own file). Each SIMD version gives its reference's bits.
#include <cstddef>
#include <cstdint>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include "reprise/core/image.hpp"
#include "reprise/warp/splat.hpp"

namespace reprise {
class StaticReprojection;
}

namespace reprise::warp {

// Interpolation's blend of one row: warped frame a (inputs *_a) merged in place into warped
// frame b (color, depth, motion): covered by both but stretched over a disocclusion on one side
// only (kCoveredStretched): the other side; else both at the same depth (kSameSurface) or both
// background: (1 - s) a + s b; a alone or in front: a; otherwise b. Motion scaled by
// motion_scale; valid = covered by either. Returns the number of pixels covered by neither.
inline constexpr float kSameSurface = 0.15f;  // relative depth difference of one surface
struct BlendRow {
    const uint8_t* covered_a;
    const uint8_t* covered_b;
    const float* depth_a;
    const glm::vec4* color_a;
    const glm::vec2* motion_a;
    float* depth;
    glm::vec4* color;
    glm::vec2* motion;
    uint8_t* valid;
    int width;
    float s;
    float motion_scale;
};
std::size_t blend_row_reference(const BlendRow& row);
std::size_t blend_row(const BlendRow& row);

// Extrapolation's static-layer test for a projection without x/y coupling (Unprojector::
// axis_aligned): a pixel is static when the camera alone explains its motion; static pixels keep
// their depth and get their displacement to the future camera, the others NaN.
struct StaticLayerTest {
    glm::mat4 projection, to_previous, to_future;  // P; view -> previous clip; view -> future clip
    float background_zv, background_w;             // the view point of depth +inf
    float width, height;                           // image size in pixels
    float tolerance2;                              // squared tolerance in pixels

    StaticLayerTest(const StaticReprojection& previous, const StaticReprojection& future,
                    int image_width, int image_height, float tolerance);
};
// Row y (width pixels of depth and motion in, depth and displacement out); returns the number of
// pixels that are not static. The reference does pixels [x_begin, x_end) of the row.
std::size_t static_layer_row_reference(const StaticLayerTest& test, int y, int x_begin, int x_end,
                                       const float* depth, const glm::vec2* motion,
                                       float* depth_out, glm::vec2* motion_out);
std::size_t static_layer_row(const StaticLayerTest& test, int y, int width, const float* depth,
                             const glm::vec2* motion, float* depth_out, glm::vec2* motion_out);

// The reverse warp's refetch of one target row: at each covered pixel q the splat's motion gives
// a first source position p = q - factor m; the source's own motion, bilinear at p, gives the
// final p, where colour is fetched bicubically (nothing written where a position leaves the
// source or a value is not finite). Source offsets are kept in 32-bit lanes: the source has fewer
// than 2^30 pixels.
struct RefetchRow {
    ImageView<const glm::vec4> color;  // the source frame
    ImageView<const glm::vec2> motion;
    float factor;
    int y;      // the target row
    int width;  // of the target row
    const uint8_t* covered;
    const glm::vec2* target_motion;
    glm::vec4* out;
};
// The reference does pixels [x_begin, x_end) of the row.
void refetch_row_reference(const RefetchRow& row, int x_begin, int x_end);
void refetch_row(const RefetchRow& row);

// Catmull-Rom colour lookups, bicubic_fetch at each position (inside the source: [0, width] x
// [0, height]), made as the grid raster and the refetch make them (bicubic-inl.h).
struct BicubicRow {
    ImageView<const glm::vec4> color;
    const glm::vec2* positions;
    int count;
    glm::vec4* out;
};
void bicubic_row_reference(const BicubicRow& row);
void bicubic_row(const BicubicRow& row);

// The displacement of each pixel to a target camera for a projection without x/y coupling
// (camera_displacement, displacement.cpp): its landing in the target minus the pixel and its
// depth there (+inf for background); NaN where the depth is NaN or negative or the point lands
// behind the target.
struct DisplacementTest {
    glm::mat4 projection, to_clip, to_view;  // P; view -> target clip; view -> target view
    float background_zv, background_w;       // the view point of depth +inf
    float width, height;                     // image size in pixels

    DisplacementTest(const StaticReprojection& to_target, int image_width, int image_height);
};
// Row y; the reference does pixels [x_begin, x_end).
void displacement_row_reference(const DisplacementTest& test, int y, int x_begin, int x_end,
                                const float* depth, glm::vec2* displacement, float* target_depth);
void displacement_row(const DisplacementTest& test, int y, int width, const float* depth,
                      glm::vec2* displacement, float* target_depth);

}  // namespace reprise::warp

namespace reprise::warp {

// Pull-push's first pull, one coarse row: each coarse pixel from its (up to) 2x2 children in fine
// rows row0 and row1 (the same row when the image ends after row0). Writes the premultiplied
// colour and weight, the farthest kept depth (with depth) and which children are holes.
struct PullRow {
    const glm::vec4* row0;
    const glm::vec4* row1;
    const uint8_t* valid0;
    const uint8_t* valid1;
    const float* depth0;  // null without depth
    const float* depth1;
    int fine_width;
    int rows;        // 2, or 1 for the last row of an odd height
    glm::vec4* out;  // (fine_width + 1) / 2 pixels
    float* out_depth;
    uint8_t* hole_bits;
};
struct PullCounts {
    std::size_t holes = 0;  // fine pixels that are holes
    std::size_t empty = 0;  // coarse pixels of weight below 1
};
// The reference does coarse pixels [i_begin, i_end).
PullCounts pull_row_reference(const PullRow& row, int i_begin, int i_end);
PullCounts pull_row(const PullRow& row);

// Pull-push's coarser pulls, one row of level s + 1 from level s (premultiplied rgb, weight in
// a, farthest kept depth): four children of weight 1 within the depth ratio give their plain
// mean, the others go through the general pull. Returns the pixels of weight below 1.
struct PullLevelRow {
    const glm::vec4* row0;
    const glm::vec4* row1;  // the same row when the level ends after row0
    const float* depth0;    // null without depth
    const float* depth1;
    int fine_width;
    int rows;        // 2, or 1
    glm::vec4* out;  // (fine_width + 1) / 2 pixels
    float* out_depth;
};
std::size_t pull_level_row_reference(const PullLevelRow& row, int i_begin, int i_end);
std::size_t pull_level_row(const PullLevelRow& row);

// FrucOptions::perceptual: a row's colour onto the display's scale and back. Encoded, r, g and b
// are the square root of their magnitude, sign kept; alpha is left as it is.
void perceptual_encode_row_reference(const glm::vec4* from, glm::vec4* to, int width);
void perceptual_encode_row(const glm::vec4* from, glm::vec4* to, int width);
void perceptual_decode_row_reference(glm::vec4* color, int width);
void perceptual_decode_row(glm::vec4* color, int width);

}  // namespace reprise::warp
