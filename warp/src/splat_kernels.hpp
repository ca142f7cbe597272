#pragma once
// The forward splat's row kernels (forward_splat.cpp) with a SIMD version chosen at run time
// (splat_kernels.cpp, Highway) beside each scalar reference; both give the same bits.
#include "band.hpp"

namespace reprise::warp {

struct SplatScatter {
    ImageView<const glm::vec4> color;
    ImageView<const float> depth;
    ImageView<const glm::vec2> motion;
    float factor;
    int footprint;
    float tol_lo, tol_hi;  // 1 -/+ depth tolerance
    int width, height;     // of the target
};

// Where one source pixel lands: target pixels [x0, x0 + nx) x [y0, y0 + ny), and the offset of
// the landing point from the centre of pixel (x0, y0).
struct SplatLanding {
    int x0, y0, nx, ny;
    float ox, oy;
};
// The z-test and the writes of one landed source pixel (depth z, motion m, colour c) in the
// band's rows, in the reference's order.
void splat_pixel(const SplatScatter& s, const Band& band, const SplatLanding& l, float z,
                 glm::vec2 m, const glm::vec4& c);

// Source pixels [x_begin, x_end) of row y offered to the band's rows, pixel by pixel in order.
void splat_row_reference(const SplatScatter& s, int y, int x_begin, int x_end, const Band& band);
void splat_row(const SplatScatter& s, int y, const Band& band);

// The vertical landing positions of source pixels [x_begin, x_end) of row y that are valid and
// land near the target, folded into [dy_min, dy_max].
void splat_extent_reference(const SplatScatter& s, int y, int x_begin, int x_end, float& dy_min,
                            float& dy_max);
// Rows of the target that source row y can touch; lo > hi when none.
void splat_rows_touched(const SplatScatter& s, float dy_min, float dy_max, int& lo, int& hi);
void splat_row_range(const SplatScatter& s, int y, int& lo, int& hi);

}  // namespace reprise::warp
