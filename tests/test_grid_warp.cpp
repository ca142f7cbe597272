// Adaptive-grid warping: analytic cases, refinement, threaded == reference, worst cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "reprise/warp/grid_warp.hpp"

using namespace reprise;
using namespace reprise::warp;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

Frame flat_frame(int w, int h, float depth, glm::vec2 motion, uint32_t seed = 1) {
    Frame f;
    f.color.resize(w, h);
    f.depth.resize(w, h, depth);
    f.motion.resize(w, h, motion);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) f.color(x, y) = {u(rng), u(rng), u(rng), 1.0f};
    return f;
}

struct Output {
    Image<glm::vec4> color;
    Image<float> depth;
    Image<glm::vec2> motion;
    Image<uint8_t> covered;
    Output(int w, int h)
        : color(w, h, glm::vec4(-7.0f)),
          depth(w, h, -3.0f),
          motion(w, h, glm::vec2(99.0f)),
          covered(w, h, 5) {}
    WarpTarget target() { return {color.view(), depth.view(), motion.view(), covered.view()}; }
};

template <class T>
bool same_bits(const Image<T>& a, const Image<T>& b) {
    return a.width() == b.width() && a.height() == b.height() &&
           std::memcmp(a.data(), b.data(), a.pixel_count() * sizeof(T)) == 0;
}

// Runs the threaded warp and the reference and checks that they agree bit for bit.
GridStats warp_both(const Frame& f, float factor, Output& out, const GridOptions& o = {}) {
    GridWarper warper;
    Output ref(out.color.width(), out.color.height());
    const GridStats fast = warper.warp(f, factor, out.target(), o);
    const GridStats slow = warper.warp_reference(f, factor, ref.target(), o);
    EXPECT_EQ(fast.cells, slow.cells);
    EXPECT_EQ(fast.covered, slow.covered);
    EXPECT_TRUE(same_bits(out.color, ref.color));
    EXPECT_TRUE(same_bits(out.depth, ref.depth));
    EXPECT_TRUE(same_bits(out.motion, ref.motion));
    EXPECT_TRUE(same_bits(out.covered, ref.covered));
    return fast;
}

// Depth steps and a sphere-like bump: a frame that refines.
Frame scene_frame(int w, int h, glm::vec2 pan, uint32_t seed) {
    Frame f = flat_frame(w, h, 10.0f, pan, seed);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (y < h / 5) {
                f.depth(x, y) = kInf;  // sky, moving with the camera rotation
                continue;
            }
            const float dx = float(x) - 0.4f * float(w), dy = float(y) - 0.6f * float(h);
            const float r = 0.2f * float(std::min(w, h));
            if (dx * dx + dy * dy < r * r) {
                f.depth(x, y) = 3.0f + 0.01f * std::sqrt(dx * dx + dy * dy);
                f.motion(x, y) = pan + glm::vec2(-6.5f, 1.25f);
            } else {
                f.depth(x, y) = 10.0f + 0.02f * float(y);
            }
        }
    return f;
}

}  // namespace

TEST(GridWarp, ZeroMotionCopiesExactly) {
    for (int min_cell : {1, 2}) {
        Frame f = scene_frame(101, 67, {0, 0}, 3);
        f.motion.resize(101, 67, glm::vec2(0.0f));
        Output out(101, 67);
        const GridStats s = warp_both(f, -0.5f, out, {.min_cell = min_cell});
        EXPECT_EQ(s.covered, 101u * 67u);
        EXPECT_TRUE(same_bits(out.color, f.color));
        EXPECT_EQ(out.covered, Image<uint8_t>(101, 67, 1));
        EXPECT_EQ(out.motion, Image<glm::vec2>(101, 67, glm::vec2(0.0f)));
        // Depth is interpolated between the vertices: close to the source's away from the edges.
        for (int y = 1; y < 66; ++y)
            for (int x = 1; x < 100; ++x) {
                float lo = kInf, hi = 0.0f;
                for (int j = -1; j <= 1; ++j)
                    for (int i = -1; i <= 1; ++i) {
                        lo = std::min(lo, f.depth(x + i, y + j));
                        hi = std::max(hi, f.depth(x + i, y + j));
                    }
                if (hi == kInf) {
                    ASSERT_TRUE(lo < kInf || out.depth(x, y) == kInf);
                } else if (hi < lo * 1.02f) {
                    ASSERT_NEAR(out.depth(x, y), f.depth(x, y), 0.01f * lo);
                }
            }
        Frame plane = flat_frame(101, 67, 4.5f, {0, 0});
        (void)warp_both(plane, -0.5f, out, {.min_cell = min_cell});
        EXPECT_TRUE(same_bits(out.depth, plane.depth));
    }
}

TEST(GridWarp, IntegerTranslationShiftsExactly) {
    const int w = 90, h = 50, k = 5;
    Frame f = flat_frame(w, h, 4.0f, {-float(k), 0.0f});
    Output out(w, h);
    const GridStats s = warp_both(f, -1.0f, out);
    EXPECT_EQ(s.covered, std::size_t(w - k) * h);
    EXPECT_EQ(s.cells, std::size_t((w + 31) / 32) * ((h + 31) / 32));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            ASSERT_EQ(out.covered(x, y), x >= k ? 1 : 0) << x << "," << y;
            if (x >= k)
                ASSERT_EQ(out.color(x, y), f.color(x - k, y)) << x << "," << y;
            else
                ASSERT_EQ(out.depth(x, y), kInf);
        }
}

TEST(GridWarp, FactorScalesMotion) {
    const int w = 40, h = 36;
    Frame f = flat_frame(w, h, 4.0f, {0.0f, 4.0f});
    Output out(w, h);
    const GridStats s = warp_both(f, -0.5f, out);  // half of a 4 px motion: 2 px up
    EXPECT_EQ(s.covered, std::size_t(w) * (h - 2));
    for (int y = 0; y < h - 2; ++y)
        for (int x = 0; x < w; ++x) ASSERT_EQ(out.color(x, y), f.color(x, y + 2)) << x << "," << y;
}

TEST(GridWarp, NearerOccluderWinsTheFoldOver) {
    for (float background : {10.0f, kInf})
        for (int min_cell : {1, 2}) {
            Frame f = flat_frame(64, 32, background, {0, 0});
            for (int y = 8; y < 24; ++y)
                for (int x = 16; x < 32; ++x) {
                    f.depth(x, y) = 1.0f;
                    f.motion(x, y) = {-6.0f, 0.0f};
                    f.color(x, y) = {1, 0, 1, 1};
                }
            Output out(64, 32);
            (void)warp_both(f, -1.0f, out, {.min_cell = min_cell});
            for (int y = 0; y < 32; ++y)
                for (int x = 0; x < 64; ++x) {
                    const bool occluder = y >= 8 && y < 24 && x >= 22 && x < 38;
                    const bool hole = y >= 8 && y < 24 && x >= 16 && x < 22;
                    if (occluder) {
                        ASSERT_EQ(out.depth(x, y), 1.0f) << x << "," << y;
                        ASSERT_EQ(out.color(x, y), glm::vec4(1, 0, 1, 1)) << x << "," << y;
                    } else if (!hole) {
                        ASSERT_EQ(out.covered(x, y), 1);
                        ASSERT_EQ(out.depth(x, y), background);
                        ASSERT_EQ(out.color(x, y), f.color(x, y)) << x << "," << y;
                    } else {
                        // The edges lie on the cell lattice: the grid tears and leaves a hole.
                        ASSERT_EQ(out.covered(x, y), 0) << x << "," << y;
                    }
                }
        }
}

TEST(GridWarp, StaysCoarseOnAFlatPlaneAndRefinesAtEdges) {
    for (auto [w, h] : {std::pair{320, 180}, std::pair{100, 33}, std::pair{32, 32}}) {
        Frame flat = flat_frame(w, h, 7.0f, {2.3f, -1.1f});
        Output out(w, h);
        const GridStats s = warp_both(flat, -0.5f, out);
        EXPECT_EQ(s.cells, std::size_t((w + 31) / 32) * ((h + 31) / 32)) << w << "x" << h;
    }
    Frame flat = flat_frame(320, 180, 7.0f, {0, 0});
    Frame edge = flat;
    for (int y = 0; y < 180; ++y)
        for (int x = 150; x < 320; ++x) edge.depth(x, y) = 9.0f;  // a depth step at x = 150
    Output out(320, 180);
    const std::size_t coarse = warp_both(flat, -0.5f, out).cells;
    const std::size_t refined = warp_both(edge, -0.5f, out).cells;
    EXPECT_GT(refined, coarse + 2 * 180 / 2 / 2);  // at least a column of 2 px cells on each side
    Frame moving = flat;
    for (int y = 90; y < 180; ++y)
        for (int x = 0; x < 320; ++x) moving.motion(x, y) = {3.0f, 0.0f};  // a motion edge
    EXPECT_GT(warp_both(moving, -0.5f, out).cells, coarse);
}

TEST(GridWarp, SmoothMotionLeavesNoCracks) {
    // The image turned by 2 degrees and enlarged by 10 % about its centre, over depth steps:
    // cells of every size meet, and away from the steps neighbouring cells must share vertices.
    const int w = 256, h = 160;
    Frame f = flat_frame(w, h, 10.0f, {0, 0});
    const float c = std::cos(0.035f), s = std::sin(0.035f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::vec2 d = glm::vec2(x + 0.5f, y + 0.5f) - glm::vec2(w / 2, h / 2);
            const glm::vec2 moved = 1.1f * glm::vec2(c * d.x - s * d.y, s * d.x + c * d.y);
            f.motion(x, y) = d - moved;  // with factor -1 the content lands at centre + moved
            if ((x / 40 + y / 40) % 2) f.depth(x, y) = 10.5f;
        }
    Output out(w, h);
    const GridStats stats = warp_both(f, -1.0f, out);
    EXPECT_GT(stats.cells, std::size_t(w / 16) * (h / 16) + 100);
    std::size_t holes = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) holes += out.covered(x, y) == 0;
    EXPECT_LT(holes, 4u * (w + h));  // tears only where the depth steps are
    std::size_t far_from_steps = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            // Where the target pixel came from: the inverse of the similarity.
            const glm::vec2 q = glm::vec2(x + 0.5f, y + 0.5f) - glm::vec2(w / 2, h / 2);
            const glm::vec2 d = glm::vec2(c * q.x + s * q.y, -s * q.x + c * q.y) / 1.1f;
            const glm::vec2 p = d + glm::vec2(w / 2, h / 2);
            auto near_step = [](float v) {
                return std::abs(std::fmod(v + 20.0f, 40.0f) - 20.0f) < 3.0f;
            };
            if (p.x < 3 || p.y < 3 || p.x > w - 3 || p.y > h - 3 || near_step(p.x) ||
                near_step(p.y))
                continue;
            ++far_from_steps;
            ASSERT_EQ(out.covered(x, y), 1) << x << "," << y;
        }
    EXPECT_GT(far_from_steps, std::size_t(w * h / 2));
}

TEST(GridWarp, BackgroundIsWarpedAndLosesToGeometry) {
    Frame f = flat_frame(64, 40, kInf, {-2.0f, 0.0f});
    for (int y = 10; y < 30; ++y)
        for (int x = 20; x < 40; ++x) f.depth(x, y) = 5.0f;  // geometry moving like the background
    Output out(64, 40);
    const GridStats s = warp_both(f, -1.0f, out);
    EXPECT_EQ(s.covered, std::size_t(62) * 40);
    EXPECT_EQ(out.depth(30, 20), 5.0f);
    EXPECT_EQ(out.depth(5, 5), kInf);
    EXPECT_EQ(out.color(30, 20), f.color(28, 20));
}

TEST(GridWarp, ThreadedEqualsReferenceOnRandomFrames) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const int sizes[][2] = {{1, 1}, {7, 3}, {3, 7}, {64, 48}, {133, 71}, {301, 203}};
    for (auto [w, h] : sizes)
        for (int trial = 0; trial < 4; ++trial) {
            Frame f = trial < 2 ? scene_frame(w, h, {1.5f * trial, -0.5f}, uint32_t(trial))
                                : flat_frame(w, h, 1.0f, {0, 0}, uint32_t(trial + w));
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const float r = u(rng);
                    if (trial >= 2) {  // noise: fold-overs and splits everywhere
                        f.depth(x, y) = r < 0.1f ? kInf : 1.0f + float(int(r * 4.0f));
                        f.motion(x, y) = {(u(rng) - 0.5f) * 12.0f, (u(rng) - 0.5f) * 12.0f};
                    }
                    const float s = u(rng);
                    if (s < 0.01f)
                        f.depth(x, y) = kNaN;
                    else if (s < 0.015f)
                        f.depth(x, y) = -kInf;
                    else if (s < 0.02f)
                        f.motion(x, y).x = kNaN;
                    else if (s < 0.025f)
                        f.motion(x, y).y = kInf;
                    else if (s < 0.03f)
                        f.motion(x, y) = {1e4f, -1e4f};
                    else if (s < 0.035f)
                        f.motion(x, y) = {3e38f, 0.0f};
                }
            for (float factor : {-0.5f, 1.0f})
                for (int min_cell : {1, 2})
                    for (int cell : {32, 8, 64}) {
                        Output out(w, h);
                        (void)warp_both(f, factor, out, {.cell = cell, .min_cell = min_cell});
                    }
        }
}

TEST(GridWarp, WorstCasesGiveNoCoverageAndNoCrash) {
    Output out(45, 29);
    for (float bad_depth : {kNaN, -kInf, -1.0f}) {
        Frame f = flat_frame(45, 29, bad_depth, {0, 0});
        const GridStats s = warp_both(f, -0.5f, out);
        EXPECT_EQ(s.covered, 0u);
        EXPECT_EQ(s.cells, 0u);
        EXPECT_EQ(out.covered, Image<uint8_t>(45, 29, 0));
        EXPECT_EQ(out.depth, Image<float>(45, 29, kInf));
    }
    for (float bad_motion : {kNaN, kInf, -kInf}) {
        Frame g = flat_frame(45, 29, 1.0f, {0.0f, bad_motion});
        EXPECT_EQ(warp_both(g, -0.5f, out).covered, 0u);
    }
    Frame far = flat_frame(45, 29, 1.0f, {1e4f, 1e4f});
    EXPECT_EQ(warp_both(far, -1.0f, out).covered, 0u);
    EXPECT_EQ(warp_both(far, 0.0f, out).covered, 45u * 29u);
    Frame huge = flat_frame(45, 29, 1.0f, {3e38f, 3e38f});
    EXPECT_EQ(warp_both(huge, -1.0f, out).covered, 0u);
    Frame one = flat_frame(1, 1, 1.0f, {0.25f, 0.0f});
    Output single(1, 1);
    EXPECT_EQ(warp_both(one, -1.0f, single).covered, 1u);
}

TEST(GridWarp, TargetOfAnotherSizeAndScratchReuse) {
    GridWarper warper;  // one warper through frames and targets of changing sizes
    const int sizes[][4] = {
        {97, 61, 97, 61}, {20, 10, 40, 30}, {300, 170, 300, 170}, {64, 64, 5, 3}, {97, 61, 97, 61}};
    for (auto [w, h, tw, th] : sizes) {
        Frame f = scene_frame(w, h, {1.25f, 0.5f}, uint32_t(w));
        Output fast(tw, th), ref(tw, th);
        const GridStats a = warper.warp(f, -0.5f, fast.target());
        const GridStats b = GridWarper().warp_reference(f, -0.5f, ref.target());
        EXPECT_EQ(a.cells, b.cells);
        EXPECT_EQ(a.covered, b.covered);
        EXPECT_TRUE(same_bits(fast.color, ref.color));
        EXPECT_TRUE(same_bits(fast.depth, ref.depth));
        EXPECT_TRUE(same_bits(fast.covered, ref.covered));
        EXPECT_LE(a.covered, std::size_t(tw) * th);
    }
    // Without a motion target.
    Frame f = scene_frame(50, 40, {1.0f, 0.0f}, 5);
    Output out(50, 40);
    WarpTarget no_motion = out.target();
    no_motion.motion = {};
    EXPECT_GT(warper.warp(f, -0.5f, no_motion).covered, 1900u);
}

TEST(GridWarp, LargeFrameRuns) {
    const int w = 8192, h = 4320;
    Frame f;
    f.color.resize(w, h, glm::vec4(0.5f));
    f.depth.resize(w, h, 3.0f);
    f.motion.resize(w, h, glm::vec2(1.25f, -0.75f));
    for (int y = 1000; y < 2000; ++y)
        for (int x = 3000; x < 4000; ++x) f.depth(x, y) = 1.0f;
    Output out(w, h);
    GridWarper warper;
    const GridStats s = warper.warp(f, -1.0f, out.target());
    EXPECT_GT(s.covered, std::size_t(w - 2) * (h - 2));
    EXPECT_LE(s.covered, std::size_t(w) * h);
    EXPECT_GT(s.cells, std::size_t(w / 32) * (h / 32));
}
