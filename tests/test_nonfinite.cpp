// NaN and infinities in every channel at every path: counted exactly, repaired at the door
// (colour: holes; depth NaN/-inf: unknown, +inf background; motion: unknown), never emitted.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "reprise/codec/codec.hpp"
#include "reprise/core/nonfinite.hpp"
#include "reprise/stereo/rig.hpp"
#include "reprise/stereo/synthesize.hpp"
#include "reprise/warp/fruc.hpp"
#include "reprise/warp/upsample.hpp"
#include "support/frames.hpp"
#include "support/nonfinite.hpp"

using namespace reprise;
using namespace reprise::warp;
using namespace reprise::test;

namespace {

void expect_counts(const NonfiniteCounts& got, const NonfiniteCounts& want, const char* what) {
    EXPECT_EQ(got.color, want.color) << what;
    EXPECT_EQ(got.depth, want.depth) << what;
    EXPECT_EQ(got.motion, want.motion) << what;
    EXPECT_EQ(got.frames, want.frames) << what;
}

}  // namespace

TEST(Nonfinite, RepairCountsAndFillsEveryChannel) {
    Frame f = sequence(1)[0];
    const NonfiniteCounts want = spoil(f, 3);
    EXPECT_GT(want.color, 150u);  // ~5 % of 5184
    EXPECT_EQ(count_nonfinite(f).color, want.color);
    NonfiniteRepair repair;
    const NonfiniteCounts got = repair.repair(f);
    expect_counts(got, want, "repair");
    EXPECT_EQ(nonfinite_in(f), 0u);
    EXPECT_EQ(count_nonfinite(f).total(), 0u);
}

TEST(Nonfinite, AllInvalidFallsBackAndOnePixelToo) {
    for (const auto& [w, h] : {std::pair(1, 1), std::pair(7, 3)}) {
        Frame f = test::constant_frame(w, h, kNaN, glm::vec2(kInf));
        f.color.fill(glm::vec4(kNaN));
        NonfiniteRepair repair;
        const NonfiniteCounts got = repair.repair(f);
        EXPECT_EQ(got.color, std::size_t(w * h));
        EXPECT_EQ(f.color(0, 0), glm::vec4(0.0f));
        EXPECT_EQ(f.depth(w - 1, h - 1), kInf);  // nothing known: background
        EXPECT_EQ(f.motion(0, h - 1), glm::vec2(0.0f));
    }
}

TEST(Nonfinite, FiniteFramePassesUntouched) {
    const Frame f = sequence(1)[0];
    NonfiniteRepair repair;
    NonfiniteCounts c;
    EXPECT_EQ(&repair.clean(f, c), &f);  // no copy: what the paths see is the frame itself
    EXPECT_EQ(c.total(), 0u);
    Frame g = f;
    EXPECT_EQ(repair.repair(g).total(), 0u);
    EXPECT_TRUE(test::same_bits(g.color, f.color));
    EXPECT_TRUE(test::same_bits(g.depth, f.depth));
    EXPECT_TRUE(test::same_bits(g.motion, f.motion));
}

TEST(Nonfinite, FrucEveryWarpFillAndModeEmitsFiniteAndCounts) {
    for (FrucMode mode : {FrucMode::Interpolate, FrucMode::Extrapolate})
        for (WarpMethod warp :
             {WarpMethod::Reverse, WarpMethod::Splat, WarpMethod::Grid, WarpMethod::Auto})
            for (FillMethod fill : {FillMethod::None, FillMethod::PullPush, FillMethod::Andreev,
                                    FillMethod::Auto, FillMethod::Patch})
                for (bool moved : {false, true}) {
                    if (warp == WarpMethod::Auto && fill == FillMethod::Patch) {
                        FrameRateConverter refused;
                        EXPECT_FALSE(FrameRateConverter::create(
                                         2, {.mode = mode, .warp = warp, .fill = fill}, refused)
                                         .ok());
                        continue;
                    }
                    const std::string what = "mode " + std::to_string(int(mode)) + " warp " +
                                             std::to_string(int(warp)) + " fill " +
                                             std::to_string(int(fill)) +
                                             (moved ? " send(&&)" : " send(const&)");
                    NonfiniteCounts want;
                    std::vector<Frame> in = spoiled_sequence(3, want);
                    FrameRateConverter converter;
                    ASSERT_TRUE(FrameRateConverter::create(
                                    2, {.mode = mode, .warp = warp, .fill = fill}, converter)
                                    .ok());
                    Frame out;
                    std::size_t outputs = 0, bad = 0;
                    for (Frame& f : in) {
                        ASSERT_TRUE(
                            (moved ? converter.send(std::move(f)) : converter.send(f)).ok());
                        while (converter.receive(out)) ++outputs, bad += nonfinite_in(out);
                    }
                    EXPECT_EQ(outputs, mode == FrucMode::Interpolate ? 5u : 6u) << what;
                    EXPECT_EQ(bad, 0u) << what;
                    expect_counts(converter.counters().nonfinite, want, what.c_str());
                }
}

TEST(Nonfinite, StereoEyeEmitsFiniteAndCounts) {
    for (stereo::StereoWarp warp : {stereo::StereoWarp::Grid, stereo::StereoWarp::Splat})
        for (stereo::StereoFill fill : {stereo::StereoFill::None, stereo::StereoFill::PullPush,
                                        stereo::StereoFill::Andreev}) {
            NonfiniteCounts want;
            std::vector<Frame> in = spoiled_sequence(2, want);
            const stereo::EyeCameras eyes =
                stereo::eye_cameras(in[1].camera, {.ipd = 0.3f}, stereo::Anchor::Left);
            stereo::StereoSynthesizer synthesizer;
            Frame out;
            const stereo::StereoStats s =
                synthesizer.synthesize(in[1], eyes.right, out, {.warp = warp, .fill = fill});
            EXPECT_EQ(nonfinite_in(out), 0u);
            EXPECT_EQ(s.nonfinite.color, count_nonfinite(in[1]).color);
            EXPECT_EQ(s.nonfinite.depth, count_nonfinite(in[1]).depth);
            EXPECT_EQ(s.nonfinite.motion, count_nonfinite(in[1]).motion);
            const stereo::StereoStats t = synthesizer.synthesize(
                in[1], eyes.right, out, {.warp = warp, .fill = fill}, &in[0]);
            EXPECT_EQ(nonfinite_in(out), 0u);
            EXPECT_EQ(t.nonfinite.frames, 2u);
            EXPECT_EQ(t.nonfinite.color,
                      count_nonfinite(in[1]).color + count_nonfinite(in[0]).color);
        }
}

TEST(Nonfinite, UpsampleEmitsFiniteAndCounts) {
    NonfiniteCounts want;
    std::vector<Frame> in = spoiled_sequence(3, want);
    SpatioTemporalUpsampler upsampler;
    Image<glm::vec4> low((kW + 1) / 2, (kH + 1) / 2), out(kW, kH);
    NonfiniteCounts got;
    for (std::size_t i = 0; i < in.size(); ++i) {
        std::size_t low_bad = 0;
        for (int y = 0; y < low.height(); ++y)
            for (int x = 0; x < low.width(); ++x) {
                low(x, y) = in[i].color(2 * x, 2 * y);
                low_bad += !finite(low(x, y));
            }
        UpsampleStats stats;
        upsampler.upsample(low.view(), glm::vec2(0.0f), in[i], out.view(), &stats);
        for (std::size_t k = 0; k < out.pixel_count(); ++k)
            EXPECT_TRUE(finite(out.data()[k])) << "frame " << i << " pixel " << k;
        EXPECT_EQ(stats.nonfinite.color, low_bad);
        got += stats.nonfinite;
    }
    EXPECT_EQ(got.depth, want.depth);
    EXPECT_EQ(got.motion, want.motion);
    EXPECT_EQ(got.frames, 3u);
}

TEST(Nonfinite, EncodeDecodeEmitsFiniteAndCounts) {
    NonfiniteCounts want;
    std::vector<Frame> in = spoiled_sequence(3, want);
    codec::Encoder encoder;
    codec::Decoder decoder;
    std::size_t decoded = 0;
    for (const Frame& f : in) {
        ASSERT_TRUE(encoder.send_frame(f).ok());
        EXPECT_EQ(nonfinite_in(encoder.reconstruction()), 0u);
        codec::Packet p;
        while (encoder.receive_packet(p) == Result::Ok) {
            ASSERT_TRUE(decoder.send_packet(p.data).ok());
            Frame out;
            while (decoder.receive_frame(out) == Result::Ok) {
                EXPECT_EQ(nonfinite_in(out), 0u);
                ++decoded;
            }
        }
    }
    EXPECT_EQ(decoded, 3u);
    expect_counts(encoder.stats().nonfinite, want, "encoder");
    EXPECT_EQ(decoder.stats().nonfinite.total(), 0u);  // the stream carried none
}
