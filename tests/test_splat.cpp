// Forward splatting: analytic cases with exact answers, threaded == reference, worst cases.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "reprise/warp/splat.hpp"
#include "support/frames.hpp"
#include "support/warp.hpp"

using namespace reprise;
using namespace reprise::warp;
using namespace reprise::test;

namespace {

using Output = WarpOutput;

using SplatFn = std::size_t (*)(const GBufferView&, float, const WarpTarget&, const SplatOptions&);
const SplatFn kBoth[] = {&splat, &splat_reference};

}  // namespace

TEST(Splat, ZeroMotionCopiesExactly) {
    for (SplatFn fn : kBoth)
        for (int footprint : {1, 2}) {
            Frame f = flat_frame(37, 21, 5.0f, {0, 0});
            f.depth(3, 4) = kInf;  // background is carried too
            f.depth(10, 10) = 1.0f;
            Output out(37, 21);
            EXPECT_EQ(fn(f, 0.7f, out.target(), {.footprint = footprint}), 37u * 21u);
            EXPECT_TRUE(same_bits(out.color, f.color));
            EXPECT_TRUE(same_bits(out.depth, f.depth));
            EXPECT_TRUE(same_bits(out.motion, f.motion));
            EXPECT_EQ(out.covered, Image<uint8_t>(37, 21, 1));
        }
}

TEST(Splat, IntegerTranslationShiftsExactly) {
    const int w = 40, h = 24, k = 3;
    for (SplatFn fn : kBoth)
        for (int footprint : {1, 2}) {
            // Content moving k px right per frame has motion (-k, 0); one frame ahead is factor -1.
            Frame f = flat_frame(w, h, 2.0f, {-float(k), 0.0f});
            Output out(w, h);
            EXPECT_EQ(fn(f, -1.0f, out.target(), {.footprint = footprint}), std::size_t(w - k) * h);
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    if (x < k) {
                        ASSERT_EQ(out.covered(x, y), 0);
                        ASSERT_EQ(out.depth(x, y), kInf);
                        ASSERT_EQ(out.color(x, y), glm::vec4(0.0f));
                    } else {
                        ASSERT_EQ(out.covered(x, y), 1);
                        ASSERT_EQ(out.color(x, y), f.color(x - k, y)) << x << "," << y;
                        ASSERT_EQ(out.motion(x, y), glm::vec2(-float(k), 0.0f));
                    }
                }
        }
}

TEST(Splat, FactorScalesMotion) {
    const int w = 30, h = 12;
    for (SplatFn fn : kBoth) {
        Frame f = flat_frame(w, h, 2.0f, {0.0f, -4.0f});
        Output out(w, h);
        // Half of a 4 px motion: content lands 2 px higher; the bottom 2 rows are uncovered.
        EXPECT_EQ(fn(f, 0.5f, out.target(), {}), std::size_t(w) * (h - 2));
        for (int y = 0; y < h - 2; ++y)
            for (int x = 0; x < w; ++x) ASSERT_EQ(out.color(x, y), f.color(x, y + 2));
        for (int x = 0; x < w; ++x) EXPECT_EQ(out.covered(x, h - 1), 0);
    }
}

TEST(Splat, NearerOccluderWinsTheOverlap) {
    for (SplatFn fn : kBoth)
        for (int footprint : {1, 2})
            for (float background : {10.0f, kInf}) {
                Frame f = flat_frame(32, 16, background, {0, 0});
                for (int y = 4; y < 12; ++y)
                    for (int x = 8; x < 16; ++x) {
                        f.depth(x, y) = 1.0f;
                        f.motion(x, y) = {-4.0f, 0.0f};
                        f.color(x, y) = {1, 0, 1, 1};
                    }
                Output out(32, 16);
                (void)fn(f, -1.0f, out.target(), {.footprint = footprint});
                for (int y = 0; y < 16; ++y)
                    for (int x = 0; x < 32; ++x) {
                        const bool occluder = y >= 4 && y < 12 && x >= 12 && x < 20;
                        const bool hole = y >= 4 && y < 12 && x >= 8 && x < 12;
                        ASSERT_EQ(out.covered(x, y), hole ? 0 : 1) << x << "," << y;
                        if (occluder) {
                            ASSERT_EQ(out.depth(x, y), 1.0f);
                            ASSERT_EQ(out.color(x, y), glm::vec4(1, 0, 1, 1));
                        } else if (!hole) {
                            ASSERT_EQ(out.depth(x, y), background);
                            ASSERT_EQ(out.color(x, y), f.color(x, y));
                        }
                    }
            }
}

TEST(Splat, SameSurfaceGoesToTheNearestLanding) {
    // A plane tilted in depth by 0.5 % per pixel, moved by a fraction: with a 2x2 footprint each
    // pixel must take the source that lands nearest its centre, not the nearest depth.
    Frame f = flat_frame(16, 4, 1.0f, {-0.25f, 0.0f});
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 16; ++x)
            f.depth(x, y) = 1.0f + 0.005f * float(x);  // the left neighbour is nearer
    Output out(16, 4);
    (void)splat(f, -1.0f, out.target(), {.footprint = 2});
    for (int x = 1; x < 16; ++x) EXPECT_EQ(out.color(x, 1), f.color(x, 1)) << x;
}

TEST(Splat, ThreadedEqualsReferenceOnRandomFrames) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const int sizes[][2] = {{1, 1}, {7, 3}, {3, 7}, {64, 48}, {133, 71}, {300, 200}};
    for (auto [w, h] : sizes)
        for (int trial = 0; trial < 3; ++trial) {
            Frame f = flat_frame(w, h, 1.0f, {0, 0}, uint32_t(trial + w));
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const float r = u(rng);
                    // Few depth levels so that ties and the tolerance rule are exercised.
                    f.depth(x, y) = r < 0.05f   ? kInf
                                    : r < 0.07f ? kNaN
                                    : r < 0.08f ? -1.0f
                                                : 1.0f + float(int(r * 4.0f));
                    const float s = u(rng);
                    glm::vec2 m{(u(rng) - 0.5f) * 16.0f, (u(rng) - 0.5f) * 16.0f};
                    if (trial == 1) m = glm::round(m);  // integer landings: many exact ties
                    if (s < 0.02f)
                        m.x = kNaN;
                    else if (s < 0.03f)
                        m.y = kInf;
                    else if (s < 0.04f)
                        m = {1e4f, -1e4f};
                    else if (s < 0.05f)
                        m = {3e38f, 0.0f};
                    f.motion(x, y) = m;
                }
            for (int footprint : {1, 2})
                for (float factor : {-0.5f, 1.0f, 0.3f}) {
                    Output fast(w, h), ref(w, h);
                    const SplatOptions o{.footprint = footprint};
                    EXPECT_EQ(splat(f, factor, fast.target(), o),
                              splat_reference(f, factor, ref.target(), o));
                    expect_same(fast, ref);
                }
        }
}

TEST(Splat, WorstCasesGiveNoCoverageAndNoCrash) {
    Output out(33, 17);
    for (float bad_depth : {kNaN, -kInf, -1.0f}) {
        Frame f = flat_frame(33, 17, bad_depth, {0, 0});
        EXPECT_EQ(splat(f, -0.5f, out.target()), 0u);
        EXPECT_EQ(out.covered, Image<uint8_t>(33, 17, 0));
        EXPECT_EQ(out.depth, Image<float>(33, 17, kInf));
    }
    for (float bad_motion : {kNaN, kInf, -kInf}) {
        Frame g = flat_frame(33, 17, 1.0f, {bad_motion, 0.0f});
        EXPECT_EQ(splat(g, -0.5f, out.target()), 0u);
    }
    Frame sky = flat_frame(33, 17, kInf, {0, 0});  // background alone is splatted
    EXPECT_EQ(splat(sky, -0.5f, out.target()), 33u * 17u);
    Frame far = flat_frame(33, 17, 1.0f, {1e4f, 1e4f});
    EXPECT_EQ(splat(far, -1.0f, out.target()), 0u);
    EXPECT_EQ(splat(far, 0.0f, out.target()), 33u * 17u);
}

TEST(Splat, TargetOfAnotherSize) {
    Frame f = flat_frame(10, 10, 1.0f, {0, 0});
    Output small(4, 3), large(20, 12);
    EXPECT_EQ(splat(f, 0.0f, small.target()), 12u);
    EXPECT_EQ(splat(f, 0.0f, large.target()), 100u);
    EXPECT_EQ(large.covered(15, 5), 0);
}

TEST(Splat, WithoutMotionTargetAndAcrossSizes) {
    for (auto [w, h] : {std::pair{50, 30}, std::pair{7, 3}, std::pair{200, 90}}) {
        Frame f = flat_frame(w, h, 2.0f, {0.4f, -0.3f});
        Output fast(w, h), ref(w, h);
        WarpTarget a = fast.target(), b = ref.target();
        a.motion = {};
        b.motion = {};
        EXPECT_EQ(splat(f, -1.0f, a), splat_reference(f, -1.0f, b));
        EXPECT_TRUE(same_bits(fast.color, ref.color));
        EXPECT_TRUE(same_bits(fast.covered, ref.covered));
        EXPECT_EQ(fast.motion, Image<glm::vec2>(w, h, glm::vec2(99.0f)));  // left alone
    }
}

TEST(Splat, LargeFrameRuns) {
    const int w = 8192, h = 4320;
    Frame f;
    f.color.assign(w, h, glm::vec4(0.5f));
    f.depth.assign(w, h, 3.0f);
    f.motion.assign(w, h, glm::vec2(1.25f, -0.75f));
    Output out(w, h);
    const std::size_t covered = splat(f, -1.0f, out.target());
    EXPECT_GT(covered, std::size_t(w - 2) * (h - 2));
    EXPECT_LE(covered, std::size_t(w) * h);
}
