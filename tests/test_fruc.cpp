// Frame-rate upconversion end to end on rendered scenes, plus its skips, cuts and bad values.
#include <gtest/gtest.h>

#include <bit>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include "reprise/core/metrics.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "reprise/warp/fruc.hpp"
#include "reprise/warp/silhouettes.hpp"
#include "support/frames.hpp"
#include "support/renderer.hpp"

using namespace reprise;
using namespace reprise::warp;

namespace {

using test::display_psnr;
using test::shared_renderer;

// Frames [first, first + count) of `scene` at `fps`.
std::vector<Frame> render(const std::string& scene_name, double fps, int first, int count,
                          int w = 384, int h = 216) {
    return test::render_scene(scene_name, count, w, h, fps, first);
}

double psnr_of(const Frame& truth, const Frame& test) {
    return display_psnr(truth.color, test.color);
}

std::vector<Frame> convert(const std::vector<Frame>& inputs, int factor, const FrucOptions& options,
                           FrucCounters* counters = nullptr) {
    FrameRateConverter converter;
    EXPECT_TRUE(FrameRateConverter::create(factor, options, converter).ok());
    std::vector<Frame> outputs;
    for (const Frame& f : inputs) {
        EXPECT_TRUE(converter.send(f).ok());
        Frame out;
        while (converter.receive(out)) outputs.push_back(out);
    }
    if (counters) *counters = converter.counters();
    return outputs;
}

}  // namespace

struct Setting {
    WarpMethod warp;
    FillMethod fill;
    const char* name;
};

class FrucMethods : public ::testing::TestWithParam<Setting> {};

// 30 -> 60 Hz on the pan scene: every synthesized frame is close to the rendered 60 Hz frame and
// much closer than repeating the previous frame.
TEST_P(FrucMethods, InterpolationBeatsFrameRepetition) {
    const std::vector<Frame> input = render("pan", 30.0, 0, 4);
    const std::vector<Frame> truth = render("pan", 60.0, 0, 7);
    FrucOptions options{
        .mode = FrucMode::Interpolate, .warp = GetParam().warp, .fill = GetParam().fill};
    FrucCounters counters;
    std::vector<Frame> out = convert(input, 2, options, &counters);
    ASSERT_EQ(out.size(), 7u);
    EXPECT_EQ(counters.linear_motion, 3u) << "a straight pan of still objects needs no true motion";
    for (int i = 1; i < 7; i += 2) {
        double ours = psnr_of(truth[i], out[i]), repeat = psnr_of(truth[i], input[i / 2]);
        std::printf("[fruc] %s frame %d: %.2f dB (repeating the previous frame: %.2f dB)\n",
                    GetParam().name, i, ours, repeat);
        EXPECT_GT(ours, repeat + 3.0) << GetParam().name << " frame " << i;
        EXPECT_GT(ours, 32.0) << GetParam().name << " frame " << i;
    }
    EXPECT_EQ(out[2].color, input[1].color) << "inputs pass through unchanged";
}

TEST_P(FrucMethods, ExtrapolationBeatsFrameRepetition) {
    const std::vector<Frame> input = render("crossing", 30.0, 10, 2);
    const std::vector<Frame> truth = render("crossing", 60.0, 20, 4);
    FrucOptions options{
        .mode = FrucMode::Extrapolate, .warp = GetParam().warp, .fill = GetParam().fill};
    FrucCounters counters;
    std::vector<Frame> out = convert(input, 2, options, &counters);
    ASSERT_EQ(out.size(), 4u);
    double ours = psnr_of(truth[3], out[3]), repeat = psnr_of(truth[3], input[1]);
    std::printf("[fruc] extrapolate %s: %.2f dB (repeating: %.2f dB)\n", GetParam().name, ours,
                repeat);
    EXPECT_GT(ours, repeat + 3.0) << GetParam().name;
    EXPECT_GT(counters.dynamic_layers, 0u) << "crossing has moving objects";
}

INSTANTIATE_TEST_SUITE_P(
    AllWarps, FrucMethods,
    ::testing::Values(Setting{WarpMethod::Grid, FillMethod::PullPush, "grid_pullpush"},
                      Setting{WarpMethod::Splat, FillMethod::PullPush, "splat_pullpush"},
                      Setting{WarpMethod::Reverse, FillMethod::Andreev, "reverse_andreev"}),
    [](const auto& setting) { return std::string(setting.param.name); });

// What the panning camera uncovers at the border continues its row before the fill: crossing's
// cars and the hud's panel cross the strip, which pull-push alone pulls the background across.
TEST(Fruc, ExtrapolatedBorderStripsContinueTheirRow) {
    // Measured: crossing 43.13 dB against 42.12, hud 46.29 against 45.82 (384x216, 9 frames).
    const struct {
        const char* scene;
        double db, gain;
    } expected[] = {{"crossing", 43.0, 0.8}, {"hud", 46.1, 0.3}};
    for (const auto& [scene, at_least, gain] : expected) {
        const std::vector<Frame> input = render(scene, 30.0, 0, 9);
        const std::vector<Frame> truth = render(scene, 60.0, 0, 18);
        double db[2] = {0.0, 0.0};
        FrucCounters counters[2];
        for (const int run : {0, 1}) {
            const FrucOptions options{.mode = FrucMode::Extrapolate,
                                      .border_run = run ? kMadeFrameBorderRun : 0};
            const std::vector<Frame> out = convert(input, 2, options, &counters[run]);
            ASSERT_EQ(out.size(), 18u);
            double error = 0.0;  // mean squared error over the made frames, as one PSNR
            for (int i = 1; i < 18; i += 2)
                error +=
                    std::pow(10.0, -psnr_of(truth[std::size_t(i)], out[std::size_t(i)]) / 10.0);
            db[run] = -10.0 * std::log10(error / 9.0);
        }
        std::printf(
            "[fruc] %s extrapolated: %.2f dB with the border strips continued (%zu px), "
            "%.2f dB by pull-push alone\n",
            scene, db[1], counters[1].border_pixels, db[0]);
        EXPECT_GE(db[1], at_least) << scene;
        EXPECT_GE(db[1] - db[0], gain) << scene;
        EXPECT_EQ(counters[0].border_pixels, 0u);
        EXPECT_GT(counters[1].border_pixels, 0u);
        EXPECT_LT(counters[1].hole_pixels, counters[0].hole_pixels);
    }
}

TEST(Fruc, InBetweenFramesBlendOnTheDisplaysScale) {
    // Measured (384x216, 9 inputs): courtyard 45.46 dB against 45.08 in linear light, specular
    // 45.39 against 44.27, crossing 48.41 against 47.93.
    const struct {
        const char* scene;
        double db, gain;
    } expected[] = {{"courtyard", 45.3, 0.25}, {"specular", 45.2, 0.9}, {"crossing", 48.2, 0.35}};
    for (const auto& [scene, at_least, gain] : expected) {
        const std::vector<Frame> input = render(scene, 30.0, 0, 9);
        const std::vector<Frame> truth = render(scene, 60.0, 0, 17);
        double db[2] = {0.0, 0.0};
        for (const bool perceptual : {false, true}) {
            const std::vector<Frame> out = convert(input, 2, {.perceptual = perceptual});
            ASSERT_EQ(out.size(), 17u);
            double error = 0.0;  // mean squared error over the made frames, as one PSNR
            for (int i = 1; i < 17; i += 2)
                error +=
                    std::pow(10.0, -psnr_of(truth[std::size_t(i)], out[std::size_t(i)]) / 10.0);
            db[perceptual] = -10.0 * std::log10(error / 8.0);
            for (int i = 0; i < 17; i += 2)  // the inputs pass through as they came
                EXPECT_EQ(out[std::size_t(i)].color, input[std::size_t(i / 2)].color);
        }
        std::printf("[fruc] %s in-between: %.2f dB on the display's scale, %.2f in linear light\n",
                    scene, db[1], db[0]);
        EXPECT_GE(db[1], at_least) << scene;
        EXPECT_GE(db[1] - db[0], gain) << scene;
    }
}

TEST(Fruc, StillFramesAreCopiedNotWarped) {
    std::vector<Frame> input = render("pan", 30.0, 0, 3, 64, 36);
    for (Frame& f : input) {
        f.color = input[0].color;
        f.motion.assign(64, 36, glm::vec2(0.0f));
    }
    for (FrucMode mode : {FrucMode::Interpolate, FrucMode::Extrapolate}) {
        FrucCounters counters;
        std::vector<Frame> out = convert(input, 4, {.mode = mode}, &counters);
        for (const Frame& f : out) EXPECT_EQ(f.color, input[0].color);
        EXPECT_EQ(counters.copied_still, counters.outputs);
        EXPECT_EQ(counters.fills + counters.grid_cells, 0u) << "nothing warped or filled";
    }
}

TEST(Fruc, PanWithoutMovingObjectsSkipsTheDynamicLayer) {
    FrucCounters counters;
    convert(render("pan", 30.0, 3, 2, 96, 54), 3, {.mode = FrucMode::Extrapolate}, &counters);
    EXPECT_EQ(counters.outputs, 4u);
    EXPECT_EQ(counters.dynamic_skipped, counters.outputs);
    EXPECT_EQ(counters.dynamic_layers, 0u);
}

TEST(Fruc, CameraCutResetsHistoryWithoutGhosts) {
    // The cut scene switches shots at 0.5 s: between frames 14 and 15 at 30 Hz.
    std::vector<Frame> input = render("cut", 30.0, 13, 4, 192, 108);
    std::vector<Frame> truth = render("cut", 60.0, 26, 8, 192, 108);
    for (FrucMode mode : {FrucMode::Interpolate, FrucMode::Extrapolate}) {
        FrucCounters counters;
        std::vector<Frame> out = convert(input, 2, {.mode = mode}, &counters);
        EXPECT_EQ(counters.cuts, 1u);
        if (mode == FrucMode::Interpolate) {
            // out: f13, (13|14), f14, (14|15) = cut, f15, (15|16), f16. The frame before the cut
            // continues the old shot: close to the truth and to f14, nothing of f15 in it.
            EXPECT_GT(psnr_of(truth[3], out[3]), 30.0);
            EXPECT_GT(psnr_of(input[1], out[3]), psnr_of(input[2], out[3]) + 10.0);
            // f15 starts its shot (its motion reaches into the old one): (15|16) uses f16 only.
            EXPECT_GT(psnr_of(truth[5], out[5]), 30.0);
        } else {
            // out: f13, x, f14, x, f15, (after the cut: a copy of f15), ...
            EXPECT_EQ(out[5].color, input[2].color);
        }
    }
}

TEST(Fruc, CreateRefusesBadSettingsNamingThemAndKeepsTheConverter) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    FrameRateConverter converter;
    ASSERT_TRUE(FrameRateConverter::create(3, {.mode = FrucMode::Extrapolate}, converter).ok());
    const std::pair<int, FrucOptions> bad[] = {{0, {}},
                                               {17, {}},
                                               {2, {.cut_misses = 1.5f}},
                                               {2, {.static_tolerance = nan}},
                                               {2, {.splat = {.footprint = 3}}},
                                               {2, {.refine = {.tile = 0}}},
                                               {2, {.warp = WarpMethod(7)}}};
    const char* named[] = {"factor 0",        "factor 17",   "cut_misses", "static_tolerance",
                           "splat.footprint", "refine.tile", "warp 7"};
    for (std::size_t i = 0; i < std::size(bad); ++i) {
        const Status s = FrameRateConverter::create(bad[i].first, bad[i].second, converter);
        ASSERT_FALSE(s.ok()) << named[i];
        EXPECT_NE(s.message().find(named[i]), std::string::npos) << s.message();
    }
    // Still the extrapolating converter at factor 3: one frame in, three out.
    ASSERT_TRUE(converter.send(render("pan", 30.0, 0, 1, 32, 18)[0]).ok());
    Frame out;
    int outputs = 0;
    while (converter.receive(out) == Result::Ok) ++outputs;
    EXPECT_EQ(outputs, 3);
}

// A backend that makes in-between frames instead of the CPU (here: b's colour) and fails once
// on request: the failing send() leaves the converter as it was, and sending the frame again
// gives what an unbroken run gives.
class FlakyBackend final : public WarpBackend {
public:
    int calls = 0, fail_at = -1;
    Status supports(const FrucOptions& o) const override {
        return o.warp == WarpMethod::Splat ? Status{} : Status::error("flaky: splat only");
    }
    Status interpolate(const GBufferView&, const GBufferView& b, float, float, const FrucOptions&,
                       Frame& out, FrucCounters&, uint64_t, uint64_t) override {
        if (calls++ == fail_at) return Status::error("flaky: the device went away");
        out.color.resize(b.color.width, b.color.height);
        for (int y = 0; y < b.color.height; ++y)
            std::copy_n(b.color.row(y), b.color.width, &out.color(0, y));
        return {};
    }
    Status extrapolate(const GBufferView& f, const glm::mat4&, const glm::mat4&, float, float,
                       const FrucOptions&, Frame& out, FrucCounters&, uint64_t) override {
        if (calls++ == fail_at) return Status::error("flaky: the device went away");
        out.color.resize(f.color.width, f.color.height);
        for (int y = 0; y < f.color.height; ++y)
            std::copy_n(f.color.row(y), f.color.width, &out.color(0, y));
        return {};
    }
};

TEST(Fruc, ABackendErrorLeavesTheConverterAsItWas) {
    const std::vector<Frame> frames = render("crossing", 30.0, 0, 3, 48, 32);
    FlakyBackend backend;
    backend.fail_at = 1;  // the second frame between inputs 0 and 1 (the first is made, queued)
    FrameRateConverter converter;
    ASSERT_TRUE(
        FrameRateConverter::create(
            3, {.warp = WarpMethod::Splat, .true_motion = false, .backend = &backend}, converter)
            .ok());
    std::vector<Frame> outputs;
    Frame out;
    ASSERT_TRUE(converter.send(frames[0]).ok());
    while (converter.receive(out)) outputs.push_back(out);
    const FrucCounters before = converter.counters();
    const Status failed = converter.send(frames[1]);
    EXPECT_NE(failed.message().find("the device went away"), std::string::npos) << failed.message();
    EXPECT_EQ(converter.receive(out), Result::NeedMoreData);  // nothing of the failed input
    EXPECT_EQ(converter.counters().inputs, before.inputs);
    EXPECT_EQ(converter.counters().outputs, before.outputs);
    for (int i = 1; i < 3; ++i) {
        ASSERT_TRUE(converter.send(frames[std::size_t(i)]).ok());
        while (converter.receive(out)) outputs.push_back(out);
    }
    ASSERT_EQ(outputs.size(), 7u);  // 0, (2 made, 1), (2 made, 2)
    EXPECT_EQ(converter.counters().inputs, 3u);
    EXPECT_EQ(converter.counters().outputs, 4u);
    EXPECT_EQ(backend.calls, 6);  // 4 made frames, and the made and the failed one rolled back
    EXPECT_EQ(display_psnr(outputs[1].color, frames[1].color), INFINITY);
    EXPECT_EQ(display_psnr(outputs[3].color, frames[1].color), INFINITY);

    FrameRateConverter refused;
    const Status grid = FrameRateConverter::create(2, {.backend = &backend}, refused);
    EXPECT_NE(grid.message().find("splat only"), std::string::npos);
}

// The same when extrapolating: a failed send leaves the converter (its previous frame too) as it
// was, and sending the frame again gives what an unbroken run gives.
TEST(Fruc, ABackendErrorWhileExtrapolatingLeavesTheConverterAsItWas) {
    const std::vector<Frame> frames = render("crossing", 30.0, 0, 3, 48, 32);
    auto run = [&](int fail_at, std::vector<Frame>& outputs) {
        FlakyBackend backend;
        backend.fail_at = fail_at;
        FrameRateConverter converter;
        EXPECT_TRUE(
            FrameRateConverter::create(
                3, {.mode = FrucMode::Extrapolate, .warp = WarpMethod::Splat, .backend = &backend},
                converter)
                .ok());
        Frame out;
        for (const Frame& f : frames) {
            Status sent = converter.send(f);
            if (!sent.ok()) {
                EXPECT_NE(sent.message().find("went away"), std::string::npos);
                EXPECT_EQ(converter.receive(out), Result::NeedMoreData);
                sent = converter.send(f);
            }
            EXPECT_TRUE(sent.ok()) << sent.message();
            while (converter.receive(out)) outputs.push_back(out);
        }
        return converter.counters();
    };
    std::vector<Frame> unbroken, broken;
    const FrucCounters a = run(-1, unbroken), b = run(3, broken);  // the 2nd of input 1
    ASSERT_EQ(broken.size(), unbroken.size());
    ASSERT_EQ(unbroken.size(), 9u);
    for (std::size_t i = 0; i < unbroken.size(); ++i)
        EXPECT_EQ(display_psnr(broken[i].color, unbroken[i].color), INFINITY) << i;
    EXPECT_EQ(b.inputs, a.inputs);
    EXPECT_EQ(b.outputs, a.outputs);
    EXPECT_EQ(b.cuts, a.cuts);
    EXPECT_EQ(b.cut_tests_skipped, a.cut_tests_skipped);
}

TEST(Fruc, TheCameraSaysWhereCutsAreAndOnlyUnknownFramesAreTested) {
    // Rendered frames 13..16 of `cut`; the renderer marks frame 15 (index 2) Cut::Yes, the others
    // No.
    const std::vector<Frame> rendered = render("cut", 30.0, 13, 4, 96, 54);
    ASSERT_EQ(rendered[2].camera.cut, Cut::Yes);
    ASSERT_EQ(rendered[3].camera.cut, Cut::No);
    auto run = [&](auto&& mark) {
        std::vector<Frame> input = rendered;
        for (std::size_t i = 0; i < input.size(); ++i) mark(i, input[i].camera.cut);
        FrucCounters counters;
        convert(input, 2, {}, &counters);
        return counters;
    };
    const FrucCounters as_rendered = run([](std::size_t, Cut&) {});
    EXPECT_EQ(as_rendered.cuts, 1u);
    EXPECT_EQ(as_rendered.cut_tests_skipped, 3u) << "every frame after the first said";
    const FrucCounters unknown = run([](std::size_t, Cut& c) { c = Cut::Unknown; });
    EXPECT_EQ(unknown.cuts, 1u) << "detected on the pixels";
    EXPECT_EQ(unknown.cut_tests_skipped, 0u);
    // The camera is believed: a cut it denies is not looked for, one it reports is taken.
    EXPECT_EQ(run([](std::size_t, Cut& c) { c = Cut::No; }).cuts, 0u);
    EXPECT_EQ(run([](std::size_t i, Cut& c) { c = i == 1 ? Cut::Yes : c; }).cuts, 2u);
}

template <class T>
bool same_bits(const Image<T>& a, const Image<T>& b) {
    return a.width() == b.width() && a.height() == b.height() &&
           std::memcmp(a.data(), b.data(), sizeof(T) * a.pixel_count()) == 0;
}

TEST(Fruc, SendingOwnedFramesGivesTheSameFrames) {
    // send(Frame&&) keeps the frame's buffers instead of copying them; across a cut, in both
    // modes and with refinement, what comes out is the same bits as send(const Frame&).
    std::vector<Frame> input = render("cut", 30.0, 12, 5, 96, 54);
    for (FrucMode mode : {FrucMode::Interpolate, FrucMode::Extrapolate}) {
        FrucCounters by_copy, by_move;
        const std::vector<Frame> expected = convert(input, 3, {.mode = mode}, &by_copy);
        FrameRateConverter converter;
        EXPECT_TRUE(FrameRateConverter::create(3, {.mode = mode}, converter).ok());
        Frame in, out;
        std::size_t k = 0;
        for (const Frame& f : input) {
            in = f;  // into buffers handed back by the previous send
            ASSERT_TRUE(converter.send(std::move(in)).ok());
            while (converter.receive(out)) {
                ASSERT_LT(k, expected.size());
                EXPECT_EQ(out.color, expected[k].color) << k;
                EXPECT_EQ(out.depth, expected[k].depth) << k;
                EXPECT_TRUE(same_bits(out.motion, expected[k].motion)) << k;  // NaN after the cut
                ++k;
            }
        }
        EXPECT_EQ(k, expected.size());
        by_move = converter.counters();
        EXPECT_EQ(by_move.cuts, 1u);
        EXPECT_EQ(by_move.outputs, by_copy.outputs);
    }
}

TEST(Fruc, BadValuesNeverSpreadAndTinyImagesWork) {
    const float nan = std::numeric_limits<float>::quiet_NaN(),
                inf = std::numeric_limits<float>::infinity();
    for (auto [w, h] : {std::pair{1, 1}, std::pair{7, 3}, std::pair{64, 36}}) {
        std::vector<Frame> input = render("crossing", 30.0, 5, 3, w, h);
        input[1].motion(0, 0) = glm::vec2(nan, 1e30f);
        input[1].depth(w / 2, h / 2) = nan;
        input[2].motion(w - 1, h - 1) = glm::vec2(1e4f, -1e4f);
        input[2].depth(0, h - 1) = -inf;
        for (FrucMode mode : {FrucMode::Interpolate, FrucMode::Extrapolate})
            for (WarpMethod warp : {WarpMethod::Grid, WarpMethod::Splat, WarpMethod::Reverse}) {
                std::vector<Frame> out = convert(input, 3, {.mode = mode, .warp = warp});
                for (const Frame& f : out)
                    for (int y = 0; y < h; ++y)
                        for (int x = 0; x < w; ++x)
                            for (int k = 0; k < 3; ++k)
                                ASSERT_TRUE(std::isfinite(f.color(x, y)[k])) << w << "x" << h;
            }
    }
}

// Under a fast orbit the pixels move on curves, and objects that tumble or accelerate move
// differently forwards than their backward motion says: the in-between frame follows the true
// motion and is measured against the linear model (the earlier frame moved along its own backward
// motion negated). With cameras: depth + the in-between camera for what the camera explains, the
// later frame's motion inverted for the rest; without (Blender's passes): the later frame's
// motion inverted wherever it lands.
void expect_true_motion_beats_linear(bool cameras) {
    for (const char* scene_name : {"pan", "crossing"}) {
        server::Scene scene;
        server::CameraPath path;
        ASSERT_TRUE(server::load_scene(scene_name, scene, path).ok());
        ASSERT_TRUE(server::parse_camera_spec("orbit:speed=2", scene, path, path).ok());
        auto frame_at = [&](int index, double fps) {
            Frame f;
            EXPECT_TRUE(shared_renderer()
                            .render_frame(scene, path, index, fps, {.width = 320, .height = 180}, f)
                            .ok());
            if (!cameras) f.camera = Camera{};
            return f;
        };
        const std::vector<Frame> input = {frame_at(2, 10.0), frame_at(3, 10.0)};
        const Frame truth = frame_at(5, 20.0);
        double psnr[2];
        for (bool exact : {false, true}) {
            const FrucOptions options{.mode = FrucMode::Interpolate, .true_motion = exact};
            FrucCounters counters;
            const std::vector<Frame> out = convert(input, 2, options, &counters);
            ASSERT_EQ(out.size(), 3u);
            psnr[exact] = psnr_of(truth, out[1]);
            EXPECT_EQ(counters.true_motion, exact ? 1u : 0u) << "an orbit is not linear";
        }
        std::printf(
            "[fruc] %s, orbit at 2 rad/s, 10 -> 20 Hz, %s cameras: true motion %.2f dB, linear "
            "%.2f dB\n",
            scene_name, cameras ? "with" : "without", psnr[1], psnr[0]);
        // Measured with one-pixel smallest cells: with cameras 30.38 / 28.81 and 23.96 / 23.40,
        // without 30.03 and 23.56 (two-pixel cells: 30.34 / 28.58 and 24.04 / 23.36, without
        // 29.90 and 23.90).
        const bool pan = std::string(scene_name) == "pan";
        EXPECT_GT(psnr[1], pan ? 29.5 : 23.5) << scene_name;
        EXPECT_GT(psnr[1], psnr[0] + (pan ? 1.0 : cameras ? 0.4 : 0.1)) << scene_name;
    }
}

TEST(FrucTrueMotion, CurvedMotionIsFollowedBetterThanLinearMotion) {
    expect_true_motion_beats_linear(true);
}

TEST(FrucWithoutCameras, InterpolationInvertsTheLaterMotion) {
    expect_true_motion_beats_linear(false);
}

// Renders without cameras (Blender's passes carry none): extrapolation moves every pixel along
// its own motion instead of leaving an empty static layer to be filled from nothing.
TEST(FrucWithoutCameras, ExtrapolationFollowsTheMotionAlone) {
    for (const char* scene : {"pan", "crossing"}) {
        const std::vector<Frame> input = render(scene, 30.0, 2, 2, 320, 180);
        const std::vector<Frame> truth = render(scene, 120.0, 12, 4, 320, 180);
        std::vector<Frame> bare = input;
        for (Frame& f : bare) f.camera = Camera{};
        const FrucOptions options{.mode = FrucMode::Extrapolate};
        const std::vector<Frame> with = convert(input, 4, options),
                                 without = convert(bare, 4, options);
        ASSERT_EQ(with.size(), 8u);
        ASSERT_EQ(without.size(), 8u);
        double sum_with = 0, sum_without = 0, sum_repeat = 0;
        for (int k = 1; k < 4; ++k) {
            sum_with += psnr_of(truth[k], with[4 + k]);
            sum_without += psnr_of(truth[k], without[4 + k]);
            sum_repeat += psnr_of(truth[k], input[1]);
        }
        std::printf(
            "[fruc] %s x4 extrapolated: %.2f dB without cameras, %.2f dB with, %.2f dB "
            "repeating\n",
            scene, sum_without / 3, sum_with / 3, sum_repeat / 3);
        // Measured: pan 39.11 / 39.11 / 32.79 (moving camera), crossing 42.40 / 42.40 / 33.42
        // (still camera, moving objects). Issue 10 asks for within 1 dB.
        EXPECT_NEAR(sum_without / 3, sum_with / 3, 1.0) << scene;
        const bool pan = std::string(scene) == "pan";
        EXPECT_GT(sum_without, sum_repeat + 3.0 * (pan ? 6.0 : 3.0)) << scene;
    }
}

// A disc drawn as the renderer draws it with anti-aliasing (colour: the mean of 4x4 samples over
// the pixel; depth and motion: the surface at the pixel centre) slides 5.6 px a frame over a
// still background shaded smoothly, as sky, walls and ground mostly are. Its edge pixels blend
// the disc with the background: widened, they travel with the disc instead of leaving a ghost
// ring where it was. (Over per-pixel noise the widened ring's pure background pixels cost more
// than the blend gains: 29.97 dB widened against 37.48 on this disc.)
Frame anti_aliased_disc(int w, int h, float cx, float step) {
    Frame f = test::constant_frame(w, h, 10.0f, {0.0f, 0.0f});
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            f.color(x, y) = {0.2f + 0.005f * float(x), 0.3f + 0.004f * float(y), 0.6f, 1.0f};
    const float cy = 32.4f, r = 12.3f;
    auto inside = [&](float x, float y) {
        return (x - cx) * (x - cx) + (y - cy) * (y - cy) < r * r;
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            int covered = 0;
            for (int j = 0; j < 4; ++j)
                for (int i = 0; i < 4; ++i)
                    covered += inside(float(x) + (float(i) + 0.5f) / 4.0f,
                                      float(y) + (float(j) + 0.5f) / 4.0f);
            const float a = float(covered) / 16.0f;
            f.color(x, y) = (1.0f - a) * f.color(x, y) + a * glm::vec4(1.0f, 0.2f, 0.2f, 1.0f);
            if (inside(float(x) + 0.5f, float(y) + 0.5f)) {
                f.depth(x, y) = 2.0f;
                f.motion(x, y) = {-step, 0.0f};
            }
        }
    return f;
}

TEST(FrucSilhouettes, APixelTakesItsNearestNeighboursSurfaceAndBadDepthsNeitherTakeNorGive) {
    const float nan = std::numeric_limits<float>::quiet_NaN(),
                inf = std::numeric_limits<float>::infinity();
    // Row 0: background, geometry at 2, geometry at 1.8 (within 15 %), background.
    // Row 1: NaN, 0, -1, geometry at 10. Row 2: geometry at 10 beside 1 (above: 10), 5, 4.
    Frame f = test::constant_frame(4, 3, 10.0f, {0.0f, 0.0f});
    const float depths[3][4] = {
        {inf, 2.0f, 1.8f, inf}, {nan, 0.0f, -1.0f, 10.0f}, {10.0f, 1.0f, 5.0f, 4.0f}};
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 4; ++x) {
            f.depth(x, y) = depths[y][x];
            f.motion(x, y) = {float(x), float(y)};
        }
    Image<float> depth;
    Image<glm::vec2> motion;
    std::size_t changed = 0;
    const GBufferView wide = widen_silhouettes(f, depth, motion, &changed);
    auto expect = [&](int x, int y, float z, glm::vec2 m) {
        if (std::isnan(z))
            EXPECT_TRUE(std::isnan(wide.depth(x, y))) << x << "," << y;
        else
            EXPECT_EQ(wide.depth(x, y), z) << x << "," << y;
        EXPECT_EQ(wide.motion(x, y), m) << x << "," << y;
    };
    expect(0, 0, 2.0f, {1, 0});  // background beside geometry
    expect(1, 0, 2.0f, {1, 0});  // 1.8 is within 15 % of 2: one surface
    expect(2, 0, 1.8f, {2, 0});
    expect(3, 0, 1.8f, {2, 0});
    expect(0, 1, nan, {0, 1});   // NaN takes nothing
    expect(1, 1, 0.0f, {1, 1});  // nor do zero and negative depths, nor do they give
    expect(2, 1, -1.0f, {2, 1});
    expect(3, 1, 4.0f, {3, 2});  // the nearest of the nearer neighbours (4 below, 1.8 is not one)
    expect(0, 2, 1.0f, {1, 2});
    expect(1, 2, 1.0f, {1, 2});
    expect(2, 2, 1.0f, {1, 2});
    expect(3, 2, 4.0f, {3, 2});
    EXPECT_EQ(changed, 5u);
    EXPECT_EQ(wide.color.data, f.color.data()) << "colour is the frame's";
    // One pixel alone (the GPU's linearity survey widens only the pixels it samples): the same.
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 4; ++x) {
            float z = 0.0f;
            glm::vec2 m{0.0f};
            widened_pixel(f, x, y, z, m);
            EXPECT_EQ(std::bit_cast<uint32_t>(z), std::bit_cast<uint32_t>(wide.depth(x, y)))
                << x << "," << y;
            EXPECT_EQ(m, wide.motion(x, y)) << x << "," << y;
        }
    // Without motion only depth is widened; without depth nothing is.
    Frame bare = f;
    bare.motion.clear();
    const GBufferView depth_only = widen_silhouettes(bare, depth, motion, &changed);
    EXPECT_TRUE(depth_only.motion.empty());
    EXPECT_EQ(depth_only.depth(0, 0), 2.0f);
    EXPECT_EQ(changed, 5u);
    bare.depth.clear();
    EXPECT_TRUE(widen_silhouettes(bare, depth, motion).depth.empty());
    // A 1x1 frame has no neighbours.
    const Frame one = test::constant_frame(1, 1, 1.0f, {0.5f, 0.5f});
    EXPECT_EQ(widen_silhouettes(one, depth, motion, &changed).depth(0, 0), 1.0f);
    EXPECT_EQ(changed, 0u);
}

TEST(FrucSilhouettes, AntiAliasedEdgesTravelWithTheSilhouette) {
    const int w = 96, h = 64;
    const float x0 = 36.3f, step = 5.6f;
    const std::vector<Frame> input = {anti_aliased_disc(w, h, x0, step),
                                      anti_aliased_disc(w, h, x0 + step, step)};
    const Frame truth = anti_aliased_disc(w, h, x0 + 0.5f * step, step);
    double psnr[2];
    for (bool widen : {false, true}) {
        FrucOptions options{.mode = FrucMode::Interpolate, .true_motion = false};
        options.widen_silhouettes = widen;
        options.refine.enabled = false;
        FrucCounters counters;
        const std::vector<Frame> out = convert(input, 2, options, &counters);
        ASSERT_EQ(out.size(), 3u);
        psnr[widen] = psnr_of(truth, out[1]);
        if (widen)
            EXPECT_GT(counters.silhouette_pixels, 2u * 70u) << "the rings of both inputs";
        else
            EXPECT_EQ(counters.silhouette_pixels, 0u);
    }
    std::printf("[fruc] anti-aliased disc, in-between frame: %.2f dB widened, %.2f dB not\n",
                psnr[1], psnr[0]);
    // Measured 53.70 dB widened, 44.52 not.
    EXPECT_GT(psnr[1], 50.0);
    EXPECT_GT(psnr[1], psnr[0] + 5.0);
}

// A converter widens each input once however many frames it makes from it (x4: three pairs,
// each input the later side of one and the earlier of the next), and every frame it makes is the
// one a converter given that pair alone makes, in both modes.
TEST(FrucSilhouettes, EachInputIsWidenedOnceForAllTheFramesMadeFromIt) {
    const std::vector<Frame> input = render("crossing", 30.0, 0, 4, 96, 64);
    std::size_t widened = 0;
    for (const Frame& f : input) {
        Image<float> depth;
        Image<glm::vec2> motion;
        std::size_t changed = 0;
        widen_silhouettes(f.view(), depth, motion, &changed);
        widened += changed;
    }
    ASSERT_GT(widened, 4u * 20u);
    for (FrucMode mode : {FrucMode::Interpolate, FrucMode::Extrapolate}) {
        SCOPED_TRACE(mode == FrucMode::Interpolate ? "interpolate" : "extrapolate");
        const FrucOptions options{.mode = mode};
        FrucCounters counters;
        const std::vector<Frame> out = convert(input, 4, options, &counters);
        ASSERT_EQ(out.size(), mode == FrucMode::Interpolate ? 13u : 16u);
        EXPECT_EQ(counters.silhouette_pixels, widened);
        for (std::size_t i = 0; i + 1 < input.size(); ++i) {
            const std::vector<Frame> alone = convert({input[i], input[i + 1]}, 4, options);
            ASSERT_EQ(alone.size(), mode == FrucMode::Interpolate ? 5u : 8u);
            const std::size_t first = mode == FrucMode::Interpolate ? 4 * i : 4 * i + 4;
            const std::size_t from = mode == FrucMode::Interpolate ? 0 : 4;
            for (std::size_t k = 1; k < 4; ++k)
                EXPECT_TRUE(test::same_bits(out[first + k].color, alone[from + k].color))
                    << "pair " << i << ", frame " << k;
        }
    }
}

// A square slides 8 px right per frame over a still background. Halfway, with two-pixel
// smallest cells each side's grid warp stretches its edge triangles over the strip the square
// uncovers on its side, in front of the background the other side saw: the in-between frame
// takes that other side there. One-pixel cells (the default) tear there instead.
TEST(FrucBlend, TheSideThatSawTheUncoveredStripIsTaken) {
    const int w = 96, h = 48, step = 8;
    const std::vector<Frame> input = {test::sliding_square_frame(w, h, 33, step),
                                      test::sliding_square_frame(w, h, 33 + step, step)};
    const Frame truth = test::sliding_square_frame(w, h, 33 + step / 2, step);
    auto psnr_with = [&](int min_cell, bool marked) {
        // Without anti-aliasing the square's neighbours are pure background: not widened.
        FrucOptions options{.mode = FrucMode::Interpolate, .true_motion = false};
        options.widen_silhouettes = false;
        options.refine.enabled = false;
        options.grid.min_cell = min_cell;
        if (!marked) options.grid.stretched_area = std::numeric_limits<float>::infinity();
        const std::vector<Frame> out = convert(input, 2, options);
        EXPECT_EQ(out.size(), 3u);
        return out.size() == 3u ? psnr_of(truth, out[1]) : 0.0;
    };
    const double marked = psnr_with(2, true), unmarked = psnr_with(2, false),
                 torn = psnr_with(FrucOptions{}.grid.min_cell, true);
    std::printf(
        "[fruc] sliding square, in-between frame: two-pixel cells %.2f dB (stretched sides not "
        "marked: %.2f dB), one-pixel cells %.2f dB\n",
        marked, unmarked, torn);
    // Measured 43.88 dB, 25.49 without the mark; one-pixel cells: identical to the truth.
    EXPECT_GT(marked, 40.0);
    EXPECT_GT(marked, unmarked + 10.0) << "the mark, not the blend, takes the right side";
    EXPECT_GT(torn, 60.0);
}
