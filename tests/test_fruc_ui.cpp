// The UI layer: carried by frames and EXR files, kept out of the warp, the nearest input's UI on
// every made frame; the built-in `hud` scene.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "reprise/core/exr.hpp"
#include "reprise/core/metrics.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "reprise/warp/fruc.hpp"
#include "support/frames.hpp"
#include "support/renderer.hpp"

using namespace reprise;
using namespace reprise::warp;

namespace {

constexpr int kW = 320, kH = 180;

std::vector<Frame> render_hud(double fps, int count) {
    server::Scene scene;
    server::CameraPath path;
    EXPECT_TRUE(server::load_scene("hud", scene, path).ok());
    std::vector<Frame> frames(count);
    for (int i = 0; i < count; ++i)
        EXPECT_TRUE(test::shared_renderer()
                        .render_frame(scene, path, i, fps, {.width = kW, .height = kH}, frames[i])
                        .ok());
    return frames;
}

std::vector<Frame> convert(const std::vector<Frame>& inputs, int factor, const FrucOptions& options,
                           FrucCounters* counters = nullptr) {
    FrameRateConverter converter;
    EXPECT_TRUE(FrameRateConverter::create(factor, options, converter).ok());
    std::vector<Frame> outputs;
    Frame out;
    for (const Frame& f : inputs) {
        EXPECT_TRUE(converter.send(f).ok());
        while (converter.receive(out)) outputs.push_back(out);
    }
    if (counters) *counters = converter.counters();
    return outputs;
}

Image<glm::vec4> composited(const Frame& f) {
    Image<glm::vec4> out(f.width(), f.height());
    composite_ui(f.color.view(), f.ui.view(), out.view());
    return out;
}

}  // namespace

TEST(HudScene, RendersTheUiApartFromTheScene) {
    const std::vector<Frame> frames = render_hud(30.0, 2);
    for (const Frame& f : frames) {
        ASSERT_EQ(f.ui.width(), kW);
        ASSERT_EQ(f.ui.height(), kH);
    }
    const Frame &a = frames[0], &b = frames[1];
    // The crosshair is opaque and static; the counter changes with every tick.
    EXPECT_EQ(a.ui(kW / 2, kH / 2).a, 1.0f);
    EXPECT_EQ(a.ui(kW / 2, kH / 2), b.ui(kW / 2, kH / 2));
    std::size_t changed = 0, translucent = 0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            changed += a.ui(x, y) != b.ui(x, y);
            translucent += a.ui(x, y).a > 0.0f && a.ui(x, y).a < 1.0f;
        }
    EXPECT_GT(changed, 50u);
    EXPECT_GT(translucent, 1000u) << "the panel lets the scene through";
    // The scene's colour holds no UI: the sky under the opaque crosshair is not its white.
    EXPECT_NE(glm::vec3(a.color(kW / 2, kH / 2)), glm::vec3(a.ui(kW / 2, kH / 2)));
}

TEST(HudScene, UiLayerRoundTripsThroughExr) {
    const Frame f = render_hud(30.0, 1)[0];
    const std::string dir = ::testing::TempDir() + "reprise_ui_exr";
    std::filesystem::create_directories(dir);
    for (ExrLayout layout : {ExrLayout::Reprise, ExrLayout::Blender}) {
        ASSERT_TRUE(write_frame(dir + "/f.exr", f, {.layout = layout}).ok());
        Frame back;
        ASSERT_TRUE(read_frame(dir + "/f.exr", back).ok());
        EXPECT_TRUE(test::same_bits(back.ui, f.ui));
        EXPECT_TRUE(test::same_bits(back.color, f.color));
    }
}

// x4: the made frames at 1/4 take the earlier input's UI, at 2/4 and 3/4 the later one's, bit
// for bit; composited, the opaque UI pixels are the UI's own; the scene beneath is what
// interpolating without any UI gives.
TEST(FrucUi, MadeFramesTakeTheNearestInputsUiUnwarped) {
    const std::vector<Frame> input = render_hud(30.0, 3);
    FrucCounters counters;
    const std::vector<Frame> layered = convert(input, 4, {}, &counters);
    ASSERT_EQ(layered.size(), 9u);
    EXPECT_EQ(counters.ui_frames, 6u);
    std::vector<Frame> bare = input;
    for (Frame& f : bare) f.ui.clear();
    const std::vector<Frame> without = convert(bare, 4, {});
    const std::vector<Frame> flat = convert(input, 4, {.composite_ui = true});
    for (int j = 0; j < 9; ++j) {
        const int k = j % 4;
        const Frame& nearest = input[j / 4 + (k >= 2 ? 1 : 0)];
        EXPECT_TRUE(test::same_bits(layered[j].ui, nearest.ui)) << "frame " << j;
        EXPECT_TRUE(test::same_bits(layered[j].color, without[j].color)) << "frame " << j;
        EXPECT_TRUE(flat[j].ui.empty());
        const Image<glm::vec4> expected = composited(layered[j]);
        EXPECT_TRUE(test::same_bits(flat[j].color, expected)) << "frame " << j;
        std::size_t opaque = 0;
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x)
                if (nearest.ui(x, y).a == 1.0f) {
                    ++opaque;
                    ASSERT_EQ(flat[j].color(x, y), nearest.ui(x, y)) << x << "," << y;
                }
        EXPECT_GT(opaque, 500u);
    }
}

// Against warping the composited colour (a UI baked into the frames): in the UI region ours
// matches the rendered 60 Hz truth far better, as UI edges do not smear.
TEST(FrucUi, UiEdgesDoNotSmear) {
    const std::vector<Frame> input = render_hud(30.0, 4);
    const std::vector<Frame> truth = render_hud(60.0, 7);
    const std::vector<Frame> ours = convert(input, 2, {.composite_ui = true});
    std::vector<Frame> baked = input;
    for (Frame& f : baked) {
        f.color = composited(f);
        f.ui.clear();
    }
    const std::vector<Frame> smeared = convert(baked, 2, {});
    double gain_sum = 0.0;
    for (int j = 1; j < 7; j += 2) {
        ASSERT_TRUE(test::same_bits(truth[j].ui, input[(j + 1) / 2].ui))
            << "the truth's UI at an in-between instant is the nearest input's";
        Image<uint8_t> mask(kW, kH);
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x)
                mask(x, y) = truth[j].ui(x, y).a > 0.0f || input[j / 2].ui(x, y).a > 0.0f;
        Image<glm::vec3> t(kW, kH), o(kW, kH), s(kW, kH);
        to_display(composited(truth[j]).view(), t.view());
        to_display(ours[j].color.view(), o.view());
        to_display(smeared[j].color.view(), s.view());
        const double p_ours = psnr(t.view(), o.view(), mask.view());
        const double p_smeared = psnr(t.view(), s.view(), mask.view());
        std::printf(
            "[fruc-ui] frame %d, UI region: %.2f dB unwarped UI, %.2f dB UI warped with "
            "the scene (%+.2f dB)\n",
            j, p_ours, p_smeared, p_ours - p_smeared);
        EXPECT_GT(p_ours, p_smeared + 3.0) << "frame " << j;
        gain_sum += p_ours - p_smeared;
    }
    std::printf("[fruc-ui] mean gain in the UI region: %+.2f dB\n", gain_sum / 3.0);
}
