#pragma once
// 8x8 integer DCT (the integer approximation used by HEVC, exact in int32), dead-zone
// quantisation and the zigzag scan. Forward output = 32 x the orthonormal DCT.
#include <array>
#include <cstdint>

namespace reprise::codec {

using Block = std::array<int32_t, 64>;  // row-major 8x8

// Residuals of at most 510 in magnitude (8-bit planes and their predictions): every sum stays
// within int32 (at most 512 * 512 * 510).
void forward_dct(const Block& in, Block& out);            // by even/odd symmetry
void forward_dct_reference(const Block& in, Block& out);  // the matrix products, same integers
void inverse_dct(const Block& in, Block& out);

// Quantiser step of qp (0..51) in sixteenths of a transform unit: 2^((qp - 4) / 6) * 32 * 16.
int32_t quant_scale(int qp);
// Levels from forward_dct's coefficients, rounding offset `deadzone16` (a fraction of a step, in
// 1/16 units). Returns the number of non-zero levels.
int quantize(const Block& coefficients, int32_t scale, int32_t deadzone16, Block& levels);
// The largest SAD of a residual whose levels (at this scale and rounding) are all 0 whatever
// its shape: the encoder leaves out its transform.
int32_t quiet_below(int32_t scale, int32_t deadzone16);
void dequantize(const Block& levels, int32_t scale, Block& coefficients);

extern const std::array<uint8_t, 64> kZigzag;  // scan index -> raster index

}  // namespace reprise::codec
