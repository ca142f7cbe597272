// Adaptive-grid warping: analytic cases, refinement, threaded == reference, worst cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>

#include "reprise/core/simd.hpp"
#include "reprise/warp/grid_warp.hpp"
#include "reprise/warp/sample.hpp"
#include "support/frames.hpp"
#include "support/warp.hpp"

using namespace reprise;
using namespace reprise::warp;
using namespace reprise::test;

namespace {

using Output = WarpOutput;

// Runs the threaded warp and the reference and checks that they agree bit for bit.
GridStats warp_both(const Frame& f, float factor, Output& out, const GridOptions& o = {}) {
    GridWarper warper;
    Output ref(out.color.width(), out.color.height());
    const GridStats fast = warper.warp(f, factor, out.target(), o);
    const GridStats slow = warper.warp_reference(f, factor, ref.target(), o);
    EXPECT_EQ(fast.cells, slow.cells);
    EXPECT_EQ(fast.covered, slow.covered);
    EXPECT_EQ(fast.nonfinite, slow.nonfinite);
    expect_same(out, ref);
    return fast;
}

// A level camera above a ground plane (the horizon above the image) that moved forward and
// sideways since the previous frame: depth varies tenfold down the image, 1/depth is affine in
// screen space and the motion is projective (neither affine nor constant).
Frame ground_frame(int w, int h) {
    const float focal = 200.0f, cx = 0.5f * float(w), cy = -20.0f, height = 1.5f;
    Frame g = flat_frame(w, h, 1.0f, {0, 0}, 7);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::vec2 p(float(x) + 0.5f, float(y) + 0.5f);
            const float z = focal * height / (p.y - cy);
            // The point in the current camera (x right, y down, z ahead), then in the previous
            // one, which stood 0.3 behind and 0.1 to the left.
            const glm::vec3 now((p.x - cx) * z / focal, height, z);
            const glm::vec3 before = now + glm::vec3(0.1f, 0.0f, 0.3f);
            g.depth(x, y) = z;
            g.motion(x, y) =
                glm::vec2(cx + focal * before.x / before.z, cy + focal * before.y / before.z) - p;
        }
    return g;
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
        f.motion.assign(101, 67, glm::vec2(0.0f));
        Output out(101, 67);
        const GridStats s = warp_both(f, -0.5f, out, {.min_cell = min_cell});
        EXPECT_EQ(s.covered, 101u * 67u);
        EXPECT_EQ(s.nonfinite, 0u);
        EXPECT_TRUE(same_bits(out.color, f.color));
        // Non-finite colour carried to the output is counted (callers sanitise only then): each
        // such source pixel reaches at most the 4 pixels whose bilinear taps include it.
        Frame odd = f;
        odd.color(5, 5).w = std::numeric_limits<float>::quiet_NaN();
        odd.color(50, 30).x = kInf;
        odd.color(100, 66).y = -kInf;
        Output odd_out(101, 67);
        const std::size_t nonfinite =
            warp_both(odd, -0.5f, odd_out, {.min_cell = min_cell}).nonfinite;
        EXPECT_GE(nonfinite, 3u);
        EXPECT_LE(nonfinite, 12u);
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

// A square that slid 8 px right, warped back to where it was: the edge triangles across its right
// edge stretch over the 8 px it uncovers, whose pixels but the one at each end are marked.
TEST(GridWarp, EdgeTrianglesStretchedOverADisocclusionAreMarked) {
    const int w = 96, h = 48, x0 = 41, step = 8;  // a 2 px cell straddles each edge
    const Frame f = sliding_square_frame(w, h, x0, step);
    Output out(w, h);
    (void)warp_both(f, 1.0f, out, {.min_cell = 2});  // one-pixel cells tear instead
    std::size_t stretched = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const bool uncovered = y >= 16 && y < 32 && x >= x0 + 16 - step && x < x0 + 16;
            stretched += out.covered(x, y) == kCoveredStretched;
            // The strip the square uncovered, away from its border rows and the square's new
            // edge (the anti-aliasing zone of one pixel), is stretched.
            if (uncovered && y >= 17 && y < 31 && x >= x0 + 16 - step + 1 && x < x0 + 15) {
                ASSERT_EQ(out.covered(x, y), kCoveredStretched) << x << "," << y;
            } else if (!(y >= 15 && y < 33 && x >= x0 - step - 1 && x < x0 + 17)) {
                ASSERT_EQ(out.covered(x, y), 1) << x << "," << y;
            }
        }
    EXPECT_LE(stretched, std::size_t(16 + 2) * (step + 2)) << "only the uncovered strip";
    (void)warp_both(f, 1.0f, out, {.min_cell = 2, .stretched_area = kInf});
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) ASSERT_EQ(out.covered(x, y), 1) << "none marked";
    // A still frame: nothing stretches.
    (void)warp_both(sliding_square_frame(w, h, x0, 0), 1.0f, out, {.min_cell = 2});
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) ASSERT_EQ(out.covered(x, y), 1);
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

namespace {

// A still magenta occluder (depth 1) over columns [0, edge) and a noise background (depth 10) that
// slides 2 px under it at factor -0.5.
Frame occluder_frame(int w, int h, int edge) {
    Frame f = flat_frame(w, h, 10.0f, {4.0f, 0.0f});
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < edge; ++x) {
            f.depth(x, y) = 1.0f;
            f.motion(x, y) = {0.0f, 0.0f};
            f.color(x, y) = {1, 0, 1, 1};
        }
    return f;
}

}  // namespace

// The occluder's last column is odd, so a block of two pixels holds both sides of its edge.
// One-pixel cells keep the occluder's column whole; two-pixel cells draw the block as one
// stretch from the occluder to the background, which covers it.
TEST(GridWarp, OnePixelCellsKeepAnOccludersColumnOffTheLattice) {
    const Frame f = occluder_frame(64, 32, 17);
    for (int min_cell : {1, 2}) {
        Output out(64, 32);
        (void)warp_both(f, -0.5f, out, {.min_cell = min_cell});
        for (int y = 2; y < 30; ++y) {
            if (min_cell == 1) {
                ASSERT_EQ(out.depth(16, y), 1.0f) << y;
                ASSERT_EQ(out.color(16, y), glm::vec4(1, 0, 1, 1)) << y;
            } else {
                ASSERT_GT(out.depth(16, y), 1.0f) << y;
            }
            ASSERT_EQ(out.depth(17, y), 10.0f) << min_cell << " " << y;
        }
    }
}

// The same edge in a starting cell clipped to two pixels at the right border (66 = 2 * 32 + 2):
// its columns were each tested against their own ends only.
TEST(GridWarp, ABorderStripTwoPixelsWideSplitsAtAnEdge) {
    const Frame f = occluder_frame(66, 40, 65);
    Output out(66, 40);
    (void)warp_both(f, -0.5f, out, {.min_cell = 1});
    for (int y = 2; y < 38; ++y) {
        ASSERT_EQ(out.depth(64, y), 1.0f) << y;
        ASSERT_EQ(out.color(64, y), glm::vec4(1, 0, 1, 1)) << y;
    }
}

TEST(GridWarp, StaysCoarseOnPlanesAndRefinesAtEdges) {
    for (auto [w, h] : {std::pair{320, 180}, std::pair{100, 33}, std::pair{32, 32}}) {
        Frame flat = flat_frame(w, h, 7.0f, {2.3f, -1.1f});
        Output out(w, h);
        const GridStats s = warp_both(flat, -0.5f, out);
        EXPECT_EQ(s.cells, std::size_t((w + 31) / 32) * ((h + 31) / 32)) << w << "x" << h;
    }
    Frame flat = flat_frame(320, 180, 7.0f, {0, 0});
    Output out(320, 180);
    const std::size_t coarse = warp_both(flat, -0.5f, out).cells;  // 10 x 6 starting cells

    // A tilted ground in perspective: within one starting cell depth changes by up to a factor
    // 2.6 and motion by up to 8 px, yet the cells interpolate it to within the thresholds and
    // stay big. (A rule on depth ratios or motion ranges splits all of them.)
    const Frame ground = ground_frame(320, 180);
    EXPECT_GT(ground.depth(0, 0) / ground.depth(0, 31), 2.5f);
    EXPECT_GT(std::abs(ground.motion(0, 179).x - ground.motion(31, 179).x), 4.0f);
    const std::size_t tilted = warp_both(ground, -0.5f, out).cells;
    std::printf("[grid] tilted ground: %zu cells (%zu starting cells)\n", tilted, coarse);
    EXPECT_LE(tilted, coarse + coarse / 2);

    Frame edge = flat;
    for (int y = 0; y < 180; ++y)
        for (int x = 150; x < 320; ++x) edge.depth(x, y) = 9.0f;  // a depth step at x = 150
    const std::size_t refined = warp_both(edge, -0.5f, out).cells;
    EXPECT_GT(refined, coarse + 2 * 180 / 2 / 2);  // at least a column of 2 px cells on each side
    Frame moving = flat;
    for (int y = 90; y < 180; ++y)
        for (int x = 0; x < 320; ++x) moving.motion(x, y) = {3.0f, 0.0f};  // a motion edge
    EXPECT_GT(warp_both(moving, -0.5f, out).cells, coarse);
    // A pole one pixel wide inside a cell, away from every corner and midpoint of it: every
    // pixel is tested, so the cells around it split down to the smallest.
    for (Frame pole : {ground, flat}) {
        const std::size_t before = warp_both(pole, -0.5f, out).cells;
        for (int y = 0; y < 180; ++y) {
            pole.depth(141, y) *= 0.5f;
            pole.motion(141, y).x += 2.0f;
        }
        EXPECT_GT(warp_both(pole, -0.5f, out).cells, before + 180 / 2);
    }
    // A curved motion field (a lens-like swirl): big cells depart from it by more than the
    // threshold, cells of 16 px do not.
    Frame curved = flat;
    for (int y = 0; y < 180; ++y)
        for (int x = 0; x < 320; ++x) {
            const float dx = float(x) - 160.0f, dy = float(y) - 90.0f;
            curved.motion(x, y) = 0.004f * glm::vec2(dx * dx, dy * dy);
        }
    const std::size_t bent = warp_both(curved, -0.5f, out).cells;
    EXPECT_GT(bent, 2 * coarse);
    EXPECT_LE(bent, 4 * coarse);
    // The thresholds are in target pixels: the same field warped by a tenth of a frame moves
    // little, and a cell may stay big.
    EXPECT_EQ(warp_both(curved, -0.1f, out).cells, coarse);
}

TEST(GridWarp, PerspectiveDepthOnATiltedPlane) {
    // The ground keeps 32 px cells (no motion to follow at factor 0) over which depth changes
    // up to 2.6-fold; drawing 1/depth linearly keeps it exact but for the vertex means, where
    // interpolating depth itself would be off by up to 6 % below the top row of cells (25 % in
    // it). Vertices on the image border take the depth of the pixels beside them, half a pixel
    // inside: the cells along the top and bottom borders are off by up to that, 2.4 % here.
    const Frame ground = ground_frame(320, 180);
    Output out(320, 180);
    EXPECT_EQ(warp_both(ground, 0.0f, out).cells, std::size_t(10 * 6));
    float inside = 0.0f, border = 0.0f;
    for (int y = 0; y < 180; ++y)
        for (int x = 0; x < 320; ++x) {
            ASSERT_EQ(out.covered(x, y), 1);
            float& worst = y >= 32 && y < 160 ? inside : border;
            worst = std::max(worst, std::abs(out.depth(x, y) / ground.depth(x, y) - 1.0f));
        }
    EXPECT_LT(inside, 5e-4f);
    EXPECT_LT(border, 0.03f);
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
    // Smooth but curved fields, where the smoothness test decides close to its thresholds, with
    // perspective-correct depth and background.
    for (auto [w, h] : {std::pair{301, 203}, std::pair{130, 67}}) {
        Frame g = ground_frame(w, h);
        for (int x = 0; x < w; ++x) g.depth(x, 0) = kInf;
        for (float factor : {-0.5f, 0.37f, -1.3f})
            for (float threshold : {0.05f, 0.25f, 1.0f}) {
                Output out(w, h);
                (void)warp_both(
                    g, factor, out,
                    {.depth_threshold = threshold * 0.04f, .motion_threshold = threshold});
            }
    }
}

TEST(GridWarp, EverySimdLevelEqualsReference) {
    struct Restore {
        ~Restore() { simd::force_target(0); }
    } restore;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (const simd::Target& target : simd::available_targets()) {
        simd::force_target(target.bits);
        SCOPED_TRACE(target.name);
        for (auto [w, h] : {std::pair{67, 45}, std::pair{133, 71}})
            for (int trial = 0; trial < 3; ++trial) {
                Frame f = trial < 2 ? scene_frame(w, h, {1.5f * trial, -0.5f}, uint32_t(trial))
                                    : flat_frame(w, h, 1.0f, {0, 0}, uint32_t(trial + w));
                if (trial == 2)
                    for (int y = 0; y < h; ++y)
                        for (int x = 0; x < w; ++x) {
                            f.depth(x, y) = u(rng) < 0.1f ? kInf : 1.0f + float(int(u(rng) * 4));
                            f.motion(x, y) = {(u(rng) - 0.5f) * 12.0f, (u(rng) - 0.5f) * 12.0f};
                        }
                for (float factor : {-0.5f, 1.0f})
                    for (int cell : {8, 32})
                        for (bool bicubic : {false, true}) {
                            Output out(w, h);
                            (void)warp_both(f, factor, out, {.cell = cell, .bicubic = bicubic});
                        }
            }
        Frame g = ground_frame(130, 67);
        Output out(130, 67);
        (void)warp_both(g, 0.37f, out);
        (void)warp_both(g, 0.37f, out, {.bicubic = true});
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
    f.color.assign(w, h, glm::vec4(0.5f));
    f.depth.assign(w, h, 3.0f);
    f.motion.assign(w, h, glm::vec2(1.25f, -0.75f));
    for (int y = 1000; y < 2000; ++y)
        for (int x = 3000; x < 4000; ++x) f.depth(x, y) = 1.0f;
    Output out(w, h);
    GridWarper warper;
    const GridStats s = warper.warp(f, -1.0f, out.target());
    EXPECT_GT(s.covered, std::size_t(w - 2) * (h - 2));
    EXPECT_LE(s.covered, std::size_t(w) * h);
    EXPECT_GT(s.cells, std::size_t(w / 32) * (h / 32));
}

TEST(GridWarp, BicubicFetchSamplesTheSourceAtTheWarpedPosition) {
    const int w = 96, h = 64;
    const glm::vec2 shift(0.375f, -0.25f);  // half of it per factor -0.5: a sub-pixel move
    Frame f = flat_frame(w, h, 4.0f, shift, 5);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float v = float((x * 7 + y * 13) % 11) / 10.0f;
            f.color(x, y) = {v, 1.0f - v, 0.5f * v, 1.0f};
        }
    Output bilinear(w, h), bicubic(w, h);
    (void)warp_both(f, -0.5f, bilinear);
    (void)warp_both(f, -0.5f, bicubic, {.bicubic = true});
    int differ = 0;
    for (int y = 3; y < h - 3; ++y)
        for (int x = 3; x < w - 3; ++x) {
            // The source point that lands on this pixel centre.
            const glm::vec2 p = glm::vec2(x + 0.5f, y + 0.5f) + 0.5f * shift;
            const glm::vec4 expected =
                bicubic_fetch(ImageView<const glm::vec4>(f.color.view()), p.x, p.y);
            ASSERT_TRUE(
                glm::all(glm::lessThan(glm::abs(bicubic.color(x, y) - expected), glm::vec4(1e-4f))))
                << x << "," << y;
            differ += bicubic.color(x, y) != bilinear.color(x, y);
        }
    EXPECT_GT(differ, (w - 6) * (h - 6) / 2);
}
