// Motion refinement of interpolation (RefineOptions): on scenes where rendered motion is not the
// motion of what is seen (moving shadows, reflections) it gains in the region it refines; where
// the vectors are right it refines nothing and changes no pixel.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "reprise/core/metrics.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "reprise/warp/fruc.hpp"
#include "reprise/warp/refine.hpp"
#include "support/frames.hpp"
#include "support/renderer.hpp"

using namespace reprise;
using namespace reprise::warp;

namespace {

using test::shared_renderer;

constexpr int kWidth = 320, kHeight = 180;

// Frame `index` of `scene_name` at `fps`, with the scene's own shading.
Frame render(const std::string& scene_name, double fps, int index) {
    server::Scene scene;
    server::CameraPath path;
    EXPECT_TRUE(server::load_scene(scene_name, scene, path).ok());
    const server::RenderSettings settings{
        .width = kWidth,
        .height = kHeight,
        .shading = scene.heavy_shading ? server::Shading::Heavy : server::Shading::Lit};
    Frame frame;
    EXPECT_TRUE(shared_renderer().render_frame(scene, path, index, fps, settings, frame).ok());
    return frame;
}

struct Made {
    Frame frame;
    Image<uint8_t> region;
    FrucCounters counters;
};

// The frame halfway between a and b.
Made between(const Frame& a, const Frame& b, const RefineOptions& refine) {
    FrucOptions options;
    options.refine = refine;
    FrameRateConverter converter;
    EXPECT_TRUE(FrameRateConverter::create(2, options, converter).ok());
    Made made;
    EXPECT_TRUE(converter.send(a).ok());
    Frame out;
    while (converter.receive(out)) {
    }
    EXPECT_TRUE(converter.send(b).ok());
    EXPECT_TRUE(converter.receive(made.frame));
    converter.refine_region(made.region);
    made.counters = converter.counters();
    return made;
}

Made between(const Frame& a, const Frame& b, bool refine) {
    return between(a, b, RefineOptions{.enabled = refine});
}

Image<glm::vec3> shown(const Frame& f) {
    Image<glm::vec3> d(f.width(), f.height());
    to_display(f.color.view(), d.view());
    return d;
}

std::size_t count(const Image<uint8_t>& mask) {
    std::size_t n = 0;
    for (int y = 0; y < mask.height(); ++y)
        for (int x = 0; x < mask.width(); ++x) n += mask(x, y) != 0;
    return n;
}

struct Gain {
    double region_off, region_on, whole_off, whole_on, share;
};

// Frames `index` and `index + 1` at 15 Hz, the truth between them at 30 Hz.
Gain measure(const std::string& scene, int index) {
    const Frame a = render(scene, 15.0, index), b = render(scene, 15.0, index + 1);
    const Image<glm::vec3> truth = shown(render(scene, 30.0, 2 * index + 1));
    const Made on = between(a, b, true), off = between(a, b, false);
    EXPECT_EQ(on.counters.refined_frames, 1u) << scene;
    EXPECT_GT(on.counters.refined_pixels, 0u) << scene;
    const Image<glm::vec3> with = shown(on.frame), without = shown(off.frame);
    Gain g{psnr(truth.view(), without.view(), on.region.view()),
           psnr(truth.view(), with.view(), on.region.view()), psnr(truth.view(), without.view()),
           psnr(truth.view(), with.view()), double(count(on.region)) / (kWidth * kHeight)};
    std::printf(
        "[refine] %s frame %d: region %.1f %% of the pixels, %.2f -> %.2f dB there (%+.2f), "
        "whole frame %.2f -> %.2f dB; %zu tiles, flow on %zu px, %zu px refined\n",
        scene.c_str(), index, 100.0 * g.share, g.region_off, g.region_on,
        g.region_on - g.region_off, g.whole_off, g.whole_on, on.counters.refine_tiles,
        on.counters.flow_pixels, on.counters.refined_pixels);
    return g;
}

}  // namespace

// A sun moving over a still scene: rendered motion is zero everywhere, the shadows move.
TEST(Refine, MovingShadowsGainInTheRegion) {
    const Gain g = measure("shadows", 3);
    EXPECT_GT(g.share, 0.01);
    EXPECT_GT(g.region_on, g.region_off + 2.0);
    EXPECT_GT(g.whole_on, g.whole_off);
}

// A mirror ball under an orbit: the reflection moves unlike the ball's surface.
TEST(Refine, ReflectionsGainInTheRegion) {
    const Gain g = measure("mirror", 3);
    EXPECT_GT(g.share, 0.01);
    EXPECT_GT(g.region_on, g.region_off + 2.0);
    EXPECT_GT(g.whole_on, g.whole_off);
}

// Where the vectors are right (a pan over still, matte objects) nothing is refined and no pixel
// changes.
TEST(Refine, NothingRefinedWhereVectorsAreRight) {
    const Frame a = render("pan", 15.0, 2), b = render("pan", 15.0, 3);
    const Made on = between(a, b, true), off = between(a, b, false);
    EXPECT_EQ(on.counters.refined_frames, 0u);
    EXPECT_EQ(on.counters.refine_skipped, 1u);
    EXPECT_EQ(on.counters.refine_tiles, 0u);
    EXPECT_EQ(on.counters.flow_pixels, 0u);
    EXPECT_EQ(count(on.region), 0u);
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x)
            ASSERT_EQ(on.frame.color(x, y), off.frame.color(x, y)) << x << "," << y;
}

// A still pair with equal pictures stays an exact copy; refinement off keeps copying a still pair
// whose pictures differ.
TEST(Refine, StillPairs) {
    const Frame a = render("shadows", 15.0, 0);
    const Made same = between(a, a, true);
    EXPECT_EQ(same.counters.copied_still, 1u);
    EXPECT_EQ(same.counters.refine_skipped, 1u);
    EXPECT_EQ(same.counters.refined_frames, 0u);
    const Frame b = render("shadows", 15.0, 1);
    const Made off = between(a, b, false);
    EXPECT_EQ(off.counters.copied_still, 1u);
    EXPECT_EQ(off.counters.refined_frames, 0u);
}

// The flow budget: boxes past the pixel share are left out and counted; a zero share refines
// nothing and changes no pixel. Without the neighbour ring the flow runs on fewer pixels.
TEST(Refine, FlowBudgetLeavesTilesOut) {
    const Frame a = render("mirror", 15.0, 3), b = render("mirror", 15.0, 4);
    const Made all = between(a, b, true), off = between(a, b, false);
    EXPECT_EQ(all.counters.refine_tiles_left_out, 0u);
    const double pixels = double(kWidth) * kHeight;
    const double share = 0.5 * double(all.counters.flow_pixels) / pixels;
    const Made half = between(a, b, RefineOptions{.max_flow_share = float(share)});
    EXPECT_LE(double(half.counters.flow_pixels), share * pixels);
    EXPECT_GT(half.counters.refine_tiles_left_out, 0u);
    EXPECT_LE(half.counters.refine_tiles_left_out, half.counters.refine_tiles);
    const Made flagged_only = between(a, b, RefineOptions{.neighbours = false});
    EXPECT_EQ(flagged_only.counters.refine_tiles, all.counters.refine_tiles);
    EXPECT_LT(flagged_only.counters.flow_pixels, all.counters.flow_pixels);
    EXPECT_GT(flagged_only.counters.refined_pixels, 0u);
    const Made none = between(a, b, RefineOptions{.max_flow_share = 0.0f});
    EXPECT_EQ(none.counters.flow_pixels, 0u);
    EXPECT_EQ(none.counters.refined_pixels, 0u);
    EXPECT_EQ(none.counters.refine_tiles_left_out, none.counters.refine_tiles);
    EXPECT_GT(none.counters.refine_tiles, 0u);
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x)
            ASSERT_EQ(none.frame.color(x, y), off.frame.color(x, y)) << x << "," << y;
}

// One box's flow is the same whatever the refiner estimated before (an OpenCV DIS object kept
// across calls gave another flow for the same pictures after a smaller box's).
TEST(Refine, FlowDoesNotDependOnEarlierFlows) {
    struct Pictures {
        Image<uint8_t> grey_a, grey_b;
        Image<glm::vec2> seed;
    };
    // The w x h at (x0, y0), as a box's crop.
    auto pictures = [](const std::vector<Frame>& f, int x0, int y0, int w, int h) {
        Pictures p{Image<uint8_t>(w, h), Image<uint8_t>(w, h), Image<glm::vec2>(w, h)};
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                p.grey_a(x, y) = MotionRefiner::grey(f[0].color(x0 + x, y0 + y));
                p.grey_b(x, y) = MotionRefiner::grey(f[1].color(x0 + x, y0 + y));
                p.seed(x, y) = f[1].motion(x0 + x, y0 + y);
            }
        return p;
    };
    // Boxes the converter met on these scenes at 96x64: a smaller one, then a whole frame.
    const Pictures pan = pictures(test::render_scene("pan", 2, 96, 64, 30.0, 3), 16, 8, 80, 56);
    const Pictures fence = pictures(test::render_scene("fence", 2, 96, 64, 30.0, 3), 0, 0, 96, 64);
    auto flow = [](MotionRefiner& refiner, const Pictures& p, Image<glm::vec2>& out) {
        refiner.flow(p.grey_b.view(), p.grey_a.view(), p.seed.view(), out);
    };
    MotionRefiner fresh, used;
    Image<glm::vec2> expected, other, got;
    flow(fresh, fence, expected);
    flow(used, pan, other);
    flow(used, fence, got);
    std::size_t moved = 0;
    for (int y = 0; y < expected.height(); ++y)
        for (int x = 0; x < expected.width(); ++x) {
            ASSERT_EQ(got(x, y), expected(x, y)) << x << "," << y;
            moved += glm::length(expected(x, y)) > 0.05f;
        }
    EXPECT_GT(moved, std::size_t(96 * 64 / 4));  // a flow that moves, not all zero
}
