// Test support: synthetic frames, bit-exact image comparison and display PSNR.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>

#include "reprise/core/frame.hpp"
#include "reprise/core/metrics.hpp"

namespace reprise::test {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Same size and the same bits in every pixel.
template <class T>
bool same_bits(const Image<T>& a, const Image<T>& b) {
    return a.width() == b.width() && a.height() == b.height() &&
           std::memcmp(a.data(), b.data(), a.pixel_count() * sizeof(T)) == 0;
}

// A w x h frame at one depth and one motion everywhere; colour zero, no normal or id.
inline Frame constant_frame(int w, int h, float depth, glm::vec2 motion) {
    Frame f;
    f.color.resize(w, h);
    f.depth.assign(w, h, depth);
    f.motion.assign(w, h, motion);
    return f;
}

// constant_frame with opaque random colour drawn from `seed`.
inline Frame flat_frame(int w, int h, float depth, glm::vec2 motion, uint32_t seed = 1) {
    Frame f = constant_frame(w, h, depth, motion);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) f.color(x, y) = {u(rng), u(rng), u(rng), 1.0f};
    return f;
}

// A still noise background (depth 10) behind a red square of `side` px (depth 2) whose top-left
// corner is at (x0, 16) and which moved `step` px to the right since the previous frame.
inline Frame sliding_square_frame(int w, int h, int x0, int step, int side = 16) {
    Frame f = flat_frame(w, h, 10.0f, {0.0f, 0.0f}, 5);
    for (int y = 16; y < std::min(h, 16 + side); ++y)
        for (int x = std::max(x0, 0); x < std::min(w, x0 + side); ++x) {
            f.color(x, y) = {1.0f, 0.2f, 0.2f, 1.0f};
            f.depth(x, y) = 2.0f;
            f.motion(x, y) = {-float(step), 0.0f};
        }
    return f;
}

// PSNR of two linear colour images on their display values.
inline double display_psnr(const Image<glm::vec4>& truth, const Image<glm::vec4>& test) {
    Image<glm::vec3> a(truth.width(), truth.height()), b(test.width(), test.height());
    to_display(truth.view(), a.view());
    to_display(test.view(), b.view());
    return psnr(a.view(), b.view());
}

}  // namespace reprise::test
