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

}  // namespace

const std::array<uint8_t, 64> kZigzag = make_zigzag();

void forward_dct(const Block& in, Block& out) {
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
        const int32_t a = std::abs(c[i]) * 16;
        const int32_t level = (a + offset) / scale;
        levels[i] = c[i] < 0 ? -level : level;
        nonzero += level != 0;
    }
    return nonzero;
}

void dequantize(const Block& levels, int32_t scale, Block& c) {
    constexpr int64_t kLimit = 1 << 20;
    for (int i = 0; i < 64; ++i) {
        const int64_t v = (int64_t(levels[i]) * scale + (levels[i] < 0 ? -8 : 8)) / 16;
        c[i] = int32_t(std::clamp(v, -kLimit, kLimit));
    }
}

}  // namespace reprise::codec
