// Test support: frames with NaN, +inf and -inf in ~5 % of every channel, and counting them.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "frames.hpp"
#include "reprise/core/nonfinite.hpp"

namespace reprise::test {

inline constexpr int kW = 96, kH = 54;  // 5184 pixels, as in the issue

inline Camera camera_at(float x) {
    Camera c;
    c.view = glm::lookAt(glm::vec3(x, 1.0f, 5.0f), glm::vec3(x, 1.0f, 0.0f), glm::vec3(0, 1, 0));
    c.prev_view = glm::lookAt(glm::vec3(x - 0.05f, 1.0f, 5.0f), glm::vec3(x - 0.05f, 1.0f, 0.0f),
                              glm::vec3(0, 1, 0));
    c.projection = glm::perspective(0.8f, float(kW) / float(kH), 0.1f, 100.0f);
    c.prev_projection = c.projection;
    return c;
}

// A near square moving over a far background, with a camera.
inline std::vector<Frame> sequence(int frames) {
    std::vector<Frame> out;
    for (int i = 0; i < frames; ++i) {
        Frame f = test::constant_frame(kW, kH, 20.0f, glm::vec2(1.0f, 0.0f));
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x)
                f.color(x, y) = {0.5f + 0.4f * std::sin(0.3f * float(x + i)),
                                 0.5f + 0.3f * std::cos(0.2f * float(y)), 0.4f, 1.0f};
        const int x0 = 20 + 8 * i;
        for (int y = 15; y < 40; ++y)
            for (int x = x0; x < x0 + 25; ++x) {
                f.depth(x, y) = 2.0f;
                f.motion(x, y) = {-8.0f, 0.0f};
                f.color(x, y) = {0.9f, 0.2f, 0.1f, 1.0f};
            }
        f.camera = camera_at(0.05f * float(i));
        f.camera.time = i / 30.0;
        f.fps = 30.0;
        out.push_back(std::move(f));
    }
    return out;
}

// NaN, +inf and -inf in ~5 % of the pixels of colour, depth and motion; returns what must be
// counted (depth +inf is background, not counted).
inline NonfiniteCounts spoil(Frame& f, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> pick(0, 59), component(0, 3);
    const float values[3] = {kNaN, kInf, -kInf};
    NonfiniteCounts c;
    for (int y = 0; y < f.height(); ++y)
        for (int x = 0; x < f.width(); ++x) {
            int r = pick(rng);
            if (r < 3) f.color(x, y)[component(rng)] = values[r], ++c.color;
            r = pick(rng);
            if (r < 3) f.depth(x, y) = values[r], c.depth += r != 1;
            r = pick(rng);
            if (r < 3) f.motion(x, y)[component(rng) % 2] = values[r], ++c.motion;
        }
    c.frames = 1;
    return c;
}

inline std::vector<Frame> spoiled_sequence(int frames, NonfiniteCounts& expected) {
    std::vector<Frame> out = sequence(frames);
    for (std::size_t i = 0; i < out.size(); ++i) expected += spoil(out[i], uint32_t(7 + i));
    return out;
}

inline bool finite(float v) { return std::isfinite(v); }
inline bool finite(const glm::vec2& v) { return finite(v.x) && finite(v.y); }
inline bool finite(const glm::vec4& v) {
    return finite(v.x) && finite(v.y) && finite(v.z) && finite(v.w);
}

// Non-finite values in a result (+inf depth is background and allowed).
inline std::size_t nonfinite_in(const Frame& f) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < f.color.pixel_count(); ++i) n += !finite(f.color.data()[i]);
    for (std::size_t i = 0; i < f.depth.pixel_count(); ++i)
        n += std::isnan(f.depth.data()[i]) || f.depth.data()[i] == -kInf;
    for (std::size_t i = 0; i < f.motion.pixel_count(); ++i) n += !finite(f.motion.data()[i]);
    return n;
}

}  // namespace reprise::test
