// Test support: warp targets that start out as garbage, and comparing two of them.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>

#include "frames.hpp"
#include "reprise/warp/splat.hpp"

namespace reprise::test {

// The images a warp writes, owned.
struct WarpOutput {
    Image<glm::vec4> color;
    Image<float> depth;
    Image<glm::vec2> motion;
    Image<uint8_t> covered;
    // Filled with garbage: the warp must initialise everything itself.
    WarpOutput(int w, int h)
        : color(w, h, glm::vec4(-7.0f)),
          depth(w, h, -3.0f),
          motion(w, h, glm::vec2(99.0f)),
          covered(w, h, 5) {}
    warp::WarpTarget target() {
        return {color.view(), depth.view(), motion.view(), covered.view()};
    }
};

// Every image of `a` and `b` agrees bit for bit.
inline void expect_same(const WarpOutput& a, const WarpOutput& b) {
    EXPECT_TRUE(same_bits(a.color, b.color));
    EXPECT_TRUE(same_bits(a.depth, b.depth));
    EXPECT_TRUE(same_bits(a.motion, b.motion));
    EXPECT_TRUE(same_bits(a.covered, b.covered));
}

}  // namespace reprise::test
