#pragma once
// Row kernels with a SIMD version chosen at run time (simd_kernels.cpp, Highway) beside their
// scalar reference (in the stage's own file). Each SIMD version gives its reference's bits: the
// codec's encoder and decoder must agree whatever level either runs at.
#include <cstddef>
#include <cstdint>

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

}  // namespace reprise::codec
