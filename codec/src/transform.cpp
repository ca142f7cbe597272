#include "transform.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace reprise::codec {

namespace {

constexpr int8_t kT[8][8] = {
    {64, 64, 64, 64, 64, 64, 64, 64},     {89, 75, 50, 18, -18, -50, -75, -89},
    {83, 36, -36, -83, -83, -36, 36, 83}, {75, -18, -89, -50, 50, 89, 18, -75},
    {64, -64, -64, 64, 64, -64, -64, 64}, {50, -89, 18, 75, -75, -18, 89, -50},
    {36, -83, 83, -36, -36, 83, -83, 36}, {18, -50, 75, -89, 89, -75, 50, -18},
};

inline int32_t round_shift(int64_t v, int s) { return int32_t((v + (int64_t(1) << (s - 1))) >> s); }

constexpr std::array<uint8_t, 64> make_zigzag() {
    std::array<uint8_t, 64> z{};
    int i = 0;
    for (int d = 0; d < 15; ++d) {
        for (int k = 0; k <= d; ++k) {
            const int y = (d % 2) ? k : d - k, x = d - y;
            if (x < 8 && y < 8) z[i++] = uint8_t(y * 8 + x);
        }
    }
    return z;
}

// The 8-point transform of v[0], v[step], ... by T's even/odd symmetry (T[k][7 - i] is
// T[k][i] for even k, -T[k][i] for odd k): the same integer sums as the product with T.
inline void forward8(const int32_t* v, int step, int32_t* out, int out_step) {
    int32_t e[4], o[4];
    for (int i = 0; i < 4; ++i) {
        e[i] = v[i * step] + v[(7 - i) * step];
        o[i] = v[i * step] - v[(7 - i) * step];
    }
    const int32_t ee0 = e[0] + e[3], ee1 = e[1] + e[2], eo0 = e[0] - e[3], eo1 = e[1] - e[2];
    out[0] = 64 * ee0 + 64 * ee1;
    out[4 * out_step] = 64 * ee0 - 64 * ee1;
    out[2 * out_step] = 83 * eo0 + 36 * eo1;
    out[6 * out_step] = 36 * eo0 - 83 * eo1;
    for (int k = 1; k < 8; k += 2)
        out[k * out_step] = kT[k][0] * o[0] + kT[k][1] * o[1] + kT[k][2] * o[2] + kT[k][3] * o[3];
}

}  // namespace

const std::array<uint8_t, 64> kZigzag = make_zigzag();

void forward_dct_reference(const Block& in, Block& out) {
    int32_t tmp[64];
    for (int k = 0; k < 8; ++k)  // tmp = T X
        for (int j = 0; j < 8; ++j) {
            int32_t s = 0;
            for (int i = 0; i < 8; ++i) s += kT[k][i] * in[i * 8 + j];
            tmp[k * 8 + j] = s;
        }
    for (int k = 0; k < 8; ++k)  // out = tmp T^T
        for (int l = 0; l < 8; ++l) {
            int32_t s = 0;
            for (int j = 0; j < 8; ++j) s += tmp[k * 8 + j] * kT[l][j];
            out[k * 8 + l] = (s + (1 << 9)) >> 10;
        }
}

void forward_dct(const Block& in, Block& out) {
    int32_t tmp[64], row[8];
    for (int j = 0; j < 8; ++j) forward8(in.data() + j, 8, tmp + j, 8);  // tmp = T X
    for (int k = 0; k < 8; ++k) {                                        // out = tmp T^T
        forward8(tmp + k * 8, 1, row, 1);
        for (int l = 0; l < 8; ++l) out[k * 8 + l] = (row[l] + (1 << 9)) >> 10;
    }
}

void inverse_dct(const Block& in, Block& out) {
    int64_t tmp[64];
    for (int i = 0; i < 8; ++i)  // tmp = T^T Y
        for (int l = 0; l < 8; ++l) {
            int64_t s = 0;
            for (int k = 0; k < 8; ++k) s += int64_t(kT[k][i]) * in[k * 8 + l];
            tmp[i * 8 + l] = s;
        }
    for (int i = 0; i < 8; ++i)  // out = tmp T
        for (int j = 0; j < 8; ++j) {
            int64_t s = 0;
            for (int l = 0; l < 8; ++l) s += tmp[i * 8 + l] * kT[l][j];
            out[i * 8 + j] = round_shift(s, 20);
        }
}

int32_t quant_scale(int qp) {
    qp = std::clamp(qp, 0, 51);
    return int32_t(std::lround(std::exp2((qp - 4) / 6.0) * 512.0));
}

int quantize(const Block& c, int32_t scale, int32_t deadzone16, Block& levels) {
    int nonzero = 0;
    // forward_dct's coefficients are below 2^17 (130,560), the offset below a step (2^17):
    // the sums stay within int32.
    const int32_t offset = int32_t(int64_t(scale) * deadzone16 / 16);
    for (int i = 0; i < 64; ++i) {
        const int32_t a = std::abs(c[i]) * 16 + offset;
        const int32_t level = a < scale ? 0 : a / scale;  // most are 0: no division for them
        levels[i] = c[i] < 0 ? -level : level;
        nonzero += level != 0;
    }
    return nonzero;
}

int32_t quiet_below(int32_t scale, int32_t deadzone16) {
    // forward_dct's coefficients are at most (89 * 89 * SAD + 512) >> 10 (T's largest entries,
    // its rounding); quantize gives a level from 16 |c| + offset >= scale on.
    const int64_t offset = int64_t(scale) * deadzone16 / 16;
    const int64_t smallest = (scale - offset + 15) / 16;  // the smallest |c| with a level
    return int32_t((1024 * smallest - 513) / (89 * 89));
}

void dequantize(const Block& levels, int32_t scale, Block& c) {
    constexpr int64_t kLimit = 1 << 20;
    for (int i = 0; i < 64; ++i) {
        const int64_t v = (int64_t(levels[i]) * scale + (levels[i] < 0 ? -8 : 8)) / 16;
        c[i] = int32_t(std::clamp(v, -kLimit, kLimit));
    }
}

}  // namespace reprise::codec
