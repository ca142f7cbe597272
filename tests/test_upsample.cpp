// Spatio-temporal upsampling (warp/upsample.hpp) and the renderer's low-resolution jittered colour.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "reprise/core/metrics.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/warp/upsample.hpp"
#include "support/frames.hpp"
#include "support/renderer.hpp"

namespace reprise {
namespace {

using test::display_psnr;
using test::kInf;
using test::kNaN;
using test::shared_renderer;
using warp::SpatioTemporalUpsampler;
using warp::UpsampleOptions;
using warp::UpsampleStats;

struct Rendered {
    std::vector<Frame> full;
    std::vector<Image<glm::vec4>> low;
    std::vector<glm::vec2> jitter;
};

Rendered render_lowres(const std::string& name, const std::string& camera, int frames, int width,
                       int height, int factor, bool unlit = false) {
    server::Scene scene;
    server::CameraPath path;
    Rendered r;
    Status status = server::load_scene(name, scene, path);
    if (status.ok() && !camera.empty()) {
        server::CameraPath fallback = path;
        status = server::parse_camera_spec(camera, scene, fallback, path);
    }
    EXPECT_TRUE(status.ok()) << status.message();
    const server::RenderSettings settings{
        .width = width,
        .height = height,
        .shading = unlit ? server::Shading::Unlit : server::Shading::Lit};
    r.full.resize(frames);
    r.low.resize(frames);
    r.jitter.resize(frames);
    for (int i = 0; i < frames; ++i) {
        status = shared_renderer().render_frame_lowres(scene, path, i, 30.0, settings, factor,
                                                       r.full[i], r.low[i], r.jitter[i]);
        EXPECT_TRUE(status.ok()) << status.message();
    }
    return r;
}

Image<glm::vec4> bilinear_resize(const Image<glm::vec4>& low, int width, int height) {
    Image<glm::vec4> out(width, height);
    const cv::Mat src(low.height(), low.width(), CV_32FC4, const_cast<glm::vec4*>(low.data()));
    cv::Mat dst(height, width, CV_32FC4, out.data());
    cv::resize(src, dst, dst.size(), 0, 0, cv::INTER_LINEAR);
    return out;
}

bool all_finite(const Image<glm::vec4>& image) {
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < image.width(); ++x) {
            const glm::vec4 c = image(x, y);
            if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z) ||
                !std::isfinite(c.w))
                return false;
        }
    return true;
}

TEST(LowresRender, SizesAndJitterCycle) {
    EXPECT_EQ(server::lowres_size(640, 360, 4), glm::ivec2(320, 180));
    EXPECT_EQ(server::lowres_size(640, 360, 2), glm::ivec2(320, 360));
    EXPECT_EQ(server::lowres_size(7, 5, 4), glm::ivec2(4, 3));
    EXPECT_EQ(server::lowres_size(1, 1, 4), glm::ivec2(1, 1));
    // 2x2: every full pixel centre of a low pixel once per four frames, then again.
    std::vector<glm::vec2> seen;
    for (int i = 0; i < 4; ++i) seen.push_back(server::lowres_jitter(64, 36, 4, i));
    for (glm::vec2 corner : {glm::vec2(-0.5f, -0.5f), glm::vec2(0.5f, -0.5f),
                             glm::vec2(-0.5f, 0.5f), glm::vec2(0.5f, 0.5f)})
        EXPECT_EQ(std::count(seen.begin(), seen.end(), corner), 1);
    EXPECT_EQ(server::lowres_jitter(64, 36, 4, 5), seen[1]);
    EXPECT_EQ(server::lowres_jitter(64, 36, 2, 0), glm::vec2(-0.5f, 0.0f));
    EXPECT_EQ(server::lowres_jitter(64, 36, 2, 1), glm::vec2(0.5f, 0.0f));
}

// A low sample equals the full render at the full pixel its jitter puts it on, better than at
// any neighbouring pixel (the texture filtering differs slightly, so not exactly).
TEST(LowresRender, SamplesLandOnFullResolutionPixelCentres) {
    const Rendered r = render_lowres("pan", "static", 4, 64, 36, 4, true);
    for (int i = 0; i < 4; ++i) {
        ASSERT_EQ(r.low[i].width(), 32);
        ASSERT_EQ(r.low[i].height(), 18);
        const glm::vec2 j = r.jitter[i];
        double error[3][3] = {};
        for (int oy = -1; oy <= 1; ++oy)
            for (int ox = -1; ox <= 1; ++ox)
                for (int v = 1; v < 17; ++v)
                    for (int u = 1; u < 31; ++u) {
                        const int x = int(std::floor((u + 0.5f) * 2.0f + j.x)) + ox;
                        const int y = int(std::floor((v + 0.5f) * 2.0f + j.y)) + oy;
                        const glm::vec4 d = glm::abs(r.low[i](u, v) - r.full[i].color(x, y));
                        error[oy + 1][ox + 1] += d.x + d.y + d.z;
                    }
        for (int oy = 0; oy < 3; ++oy)
            for (int ox = 0; ox < 3; ++ox)
                if (ox != 1 || oy != 1) {
                    EXPECT_LT(2.0 * error[1][1], error[oy][ox])
                        << "frame " << i << " offset " << ox - 1 << "," << oy - 1;
                }
    }
}

// Mean of frames 4..9 of pan at 256x144, measured 2026-12-01: 1/4 of the pixels upsampled
// 33.54 dB, bilinear cv::resize 28.07 dB; 1/2: 37.92 dB, bilinear 33.33 dB. The floors sit about
// 1 dB below.
TEST(Upsample, RenderedScenePsnrFloorAndMarginOverBilinear) {
    struct Case {
        int factor;
        double floor, margin;
    };
    for (const Case c : {Case{4, 32.5, 4.5}, Case{2, 36.9, 3.6}}) {
        const int w = 256, h = 144, frames = 10;
        const Rendered r = render_lowres("pan", "", frames, w, h, c.factor);
        SpatioTemporalUpsampler upsampler;
        Image<glm::vec4> out(w, h);
        double ours = 0.0, bilinear = 0.0;
        int counted = 0;
        for (int i = 0; i < frames; ++i) {
            UpsampleStats stats;
            upsampler.upsample(r.low[i].view(), r.jitter[i], r.full[i], out.view(), &stats);
            if (i < 4) continue;  // the history fills up over the jitter cycle
            EXPECT_GT(stats.history_used, int64_t(w) * h / 2);
            ours += display_psnr(r.full[i].color, out);
            bilinear += display_psnr(r.full[i].color, bilinear_resize(r.low[i], w, h));
            ++counted;
        }
        ours /= counted;
        bilinear /= counted;
        std::printf("pan 256x144 1/%d: upsampled %.2f dB, bilinear %.2f dB\n", c.factor, ours,
                    bilinear);
        EXPECT_GT(ours, c.floor) << "1/" << c.factor;
        EXPECT_GT(ours, bilinear + c.margin) << "1/" << c.factor;
    }
}

// A still camera: the history gathers every full pixel over the jitter cycle, and the error falls
// well below the spatial-only first frame (measured: 30.35 -> 33.89 dB at 192x108 over 12 frames).
TEST(Upsample, StillCameraConvergesTowardsTheFullRender) {
    const int w = 192, h = 108, frames = 12;
    const Rendered r = render_lowres("pan", "static", frames, w, h, 4);
    SpatioTemporalUpsampler upsampler;
    Image<glm::vec4> out(w, h);
    std::vector<double> psnr;
    for (int i = 0; i < frames; ++i) {
        upsampler.upsample(r.low[i].view(), r.jitter[i], r.full[i], out.view());
        psnr.push_back(display_psnr(r.full[i].color, out));
    }
    std::printf("still camera: frame 0 %.2f dB, frame 3 %.2f dB, frame %d %.2f dB\n", psnr[0],
                psnr[3], frames - 1, psnr.back());
    EXPECT_GT(psnr.back(), psnr[0] + 2.5);
    EXPECT_GE(psnr.back(), psnr[3] - 0.1);
}

// A synthetic pair of frames: history colour A everywhere, then colour B, with `region` new this
// frame (another id, or a depth jump). Without clamping, only the new region must equal B.
struct TwoFrames {
    Frame previous, current;
    Image<glm::vec4> low_a, low_b;
};

TwoFrames two_frames(int w, int h, glm::vec4 a, glm::vec4 b) {
    TwoFrames t;
    t.previous = test::constant_frame(w, h, 10.0f, glm::vec2(0.0f));
    t.previous.id.assign(w, h, 1u);
    t.previous.normal.assign(w, h, glm::vec3(0.0f, 0.0f, 1.0f));
    t.current = t.previous;
    t.low_a.assign(w / 2, h / 2, a);
    t.low_b.assign(w / 2, h / 2, b);
    return t;
}

bool inside(int x, int y) { return x >= 8 && x < 16 && y >= 4 && y < 12; }

TEST(Upsample, NewIdOrDisocclusionTakesNoHistory) {
    const int w = 32, h = 16;
    const glm::vec4 a(0.8f, 0.1f, 0.1f, 1.0f), b(0.1f, 0.1f, 0.8f, 1.0f);
    for (bool by_id : {true, false}) {
        TwoFrames t = two_frames(w, h, a, b);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                if (inside(x, y)) {
                    if (by_id)
                        t.current.id(x, y) = 2u;
                    else
                        t.current.depth(x, y) = 5.0f;  // a surface in front of the old one
                }
        SpatioTemporalUpsampler upsampler({.history_clamp = -1.0f});
        Image<glm::vec4> out(w, h);
        upsampler.upsample(t.low_a.view(), {-0.5f, -0.5f}, t.previous, out.view());
        UpsampleStats stats;
        upsampler.upsample(t.low_b.view(), {0.5f, 0.5f}, t.current, out.view(), &stats);
        EXPECT_EQ(stats.history_rejected, 64) << (by_id ? "id" : "depth");
        EXPECT_EQ(stats.history_used, int64_t(w) * h - 64);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                if (inside(x, y)) {
                    EXPECT_NEAR(out(x, y).x, b.x, 1e-5f) << x << "," << y;
                    EXPECT_NEAR(out(x, y).z, b.z, 1e-5f) << x << "," << y;
                } else {
                    EXPECT_GT(out(x, y).x, b.x + 0.05f)
                        << x << "," << y;  // history of A blended in
                }
            }
    }
}

TEST(Upsample, HistoryFollowsMotion) {
    // A two-colour edge moves 4 pixels right: with the right motion the history lands where its
    // surface went; with zero motion it drags the old edge along.
    const int w = 32, h = 8;
    Image<glm::vec4> low(w / 2, h / 2), shifted(w / 2, h / 2), first(w, h);
    for (int v = 0; v < h / 2; ++v)
        for (int u = 0; u < w / 2; ++u) {
            low(u, v) = u < 6 ? glm::vec4(1.0f) : glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
            shifted(u, v) = u < 8 ? glm::vec4(1.0f) : glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
        }
    double error[2] = {0.0, 0.0};
    float worst[2] = {0.0f, 0.0f};
    for (int moving = 0; moving < 2; ++moving) {
        Frame f = test::constant_frame(w, h, 10.0f, glm::vec2(0.0f));
        SpatioTemporalUpsampler upsampler({.history_clamp = -1.0f});
        upsampler.upsample(low.view(), {-0.5f, -0.5f}, f, first.view());
        if (moving) f.motion.assign(w, h, glm::vec2(-4.0f, 0.0f));  // it was 4 pixels further left
        Image<glm::vec4> out(w, h);
        upsampler.upsample(shifted.view(), {-0.5f, -0.5f}, f, out.view());
        for (int x = 8; x < w; ++x) {
            const float e = std::abs(out(x, 4).x - first(x - 4, 4).x);
            error[moving] += e;
            worst[moving] = std::max(worst[moving], e);
        }
    }
    EXPECT_LT(worst[1], 0.1f);
    EXPECT_LT(error[1], 0.25 * error[0]);
}

TEST(Upsample, ConstantColorStaysExact) {
    const int w = 21, h = 13;
    Frame f = test::flat_frame(w, h, 3.0f, glm::vec2(0.7f, -0.3f));
    f.id.assign(w, h, 1u);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            f.depth(x, y) = x < 7 ? kInf : 1.0f + 0.3f * float(x * y);
            if (x > 15) f.id(x, y) = 3u;
        }
    const glm::vec4 c(0.25f, 0.5f, 0.75f, 1.0f);
    Image<glm::vec4> low(11, 7, c), out(w, h);
    SpatioTemporalUpsampler upsampler;
    for (int i = 0; i < 5; ++i) {
        upsampler.upsample(low.view(), server::lowres_jitter(w, h, 4, i), f, out.view());
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                ASSERT_NEAR(out(x, y).x, c.x, 1e-5f);
                ASSERT_NEAR(out(x, y).y, c.y, 1e-5f);
                ASSERT_NEAR(out(x, y).z, c.z, 1e-5f);
                ASSERT_EQ(out(x, y).w, x < 7 ? 0.0f : 1.0f);
            }
    }
}

TEST(Upsample, NonFiniteColorOrDepthDoesNotSpread) {
    const int w = 40, h = 24;
    Frame f = test::flat_frame(w, h, 4.0f, glm::vec2(0.0f));
    f.id.assign(w, h, 1u);
    Image<glm::vec4> low(w / 2, h / 2), out(w, h), reference(w, h);
    for (int v = 0; v < h / 2; ++v)
        for (int u = 0; u < w / 2; ++u) low(u, v) = glm::vec4(0.05f * u, 0.03f * v, 0.5f, 1.0f);
    Image<glm::vec4> bad_low = low;
    bad_low(5, 5) = glm::vec4(kNaN, 0.0f, 0.0f, 1.0f);
    bad_low(14, 6) = glm::vec4(kInf, -kInf, 0.0f, 1.0f);
    Frame bad = f;
    bad.depth(30, 3) = kNaN;
    bad.depth(31, 3) = -kInf;
    bad.motion(20, 20) = glm::vec2(kNaN, 1.0f);
    bad.motion(21, 20) = glm::vec2(3e38f, -3e38f);
    bad.normal.assign(w, h, glm::vec3(0.0f, 0.0f, 1.0f));
    f.normal = bad.normal;
    bad.normal(2, 20) = glm::vec3(kNaN);
    SpatioTemporalUpsampler clean, dirty;
    for (int i = 0; i < 6; ++i) {
        const glm::vec2 j = server::lowres_jitter(w, h, 4, i);
        clean.upsample(low.view(), j, f, reference.view());
        UpsampleStats stats;
        dirty.upsample(bad_low.view(), j, bad, out.view(), &stats);
        EXPECT_EQ(stats.nonfinite_samples > 0, true);
        ASSERT_TRUE(all_finite(out)) << "frame " << i;
        // Away from the bad samples (their 2x2 footprints and one low pixel around), identical.
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const bool near_nan = std::abs(x - 11) <= 5 && std::abs(y - 11) <= 5;
                const bool near_inf = std::abs(x - 29) <= 5 && std::abs(y - 13) <= 5;
                const bool near_depth = std::abs(x - 30) <= 5 && std::abs(y - 3) <= 5;
                const bool near_normal = std::abs(x - 2) <= 5 && std::abs(y - 20) <= 5;
                // A pixel without history has the largest temporal gradient, which the gradient's
                // low-pass (radius 3) spreads a little.
                const bool near_motion = x >= 17 && x <= 24 && std::abs(y - 20) <= 3;
                if (near_nan || near_inf || near_depth || near_normal || near_motion) continue;
                // The gradient low-pass reaches 3 pixels further; the result stays close.
                EXPECT_NEAR(out(x, y).x, reference(x, y).x, 0.02f)
                    << x << "," << y << " frame " << i;
            }
    }
}

// The final pass reuses the gradient pass's taps; recomputing them (the reference) gives the
// same bits, on a rendered sequence with motion, edges and disocclusions.
TEST(Upsample, CachedTapsMatchTheReference) {
    const int w = 96, h = 54, frames = 5;
    const Rendered r = render_lowres("crossing", "", frames, w, h, 2);
    SpatioTemporalUpsampler cached, reference({.recompute_taps = true});
    Image<glm::vec4> a(w, h), b(w, h);
    for (int i = 0; i < frames; ++i) {
        cached.upsample(r.low[i].view(), r.jitter[i], r.full[i], a.view());
        reference.upsample(r.low[i].view(), r.jitter[i], r.full[i], b.view());
        ASSERT_TRUE(test::same_bits(a, b)) << "frame " << i;
    }
}

TEST(Upsample, TinyAndOddSizes) {
    struct Case {
        int w, h, lw, lh;
    };
    for (const Case c : {Case{1, 1, 1, 1}, Case{7, 5, 4, 3}, Case{7, 5, 4, 5}, Case{7, 5, 1, 1},
                         Case{3, 9, 2, 9}, Case{2, 1, 1, 1}}) {
        Frame f = test::flat_frame(c.w, c.h, 2.0f, glm::vec2(0.5f, -0.25f));
        f.id.assign(c.w, c.h, 1u);
        f.normal.assign(c.w, c.h, glm::vec3(0.0f, 1.0f, 0.0f));
        Image<glm::vec4> low(c.lw, c.lh), out(c.w, c.h);
        for (int v = 0; v < c.lh; ++v)
            for (int u = 0; u < c.lw; ++u) low(u, v) = glm::vec4(0.1f * u, 0.2f * v, 0.3f, 1.0f);
        SpatioTemporalUpsampler upsampler;
        for (int i = 0; i < 4; ++i) {
            UpsampleStats stats;
            upsampler.upsample(low.view(), {0.25f * i - 0.5f, 0.5f - 0.25f * i}, f, out.view(),
                               &stats);
            EXPECT_EQ(stats.unresolved, 0);
            ASSERT_TRUE(all_finite(out)) << c.w << "x" << c.h << " from " << c.lw << "x" << c.lh;
        }
        upsampler.reset();
        upsampler.upsample(low.view(), {0.0f, 0.0f}, f, out.view());
        ASSERT_TRUE(all_finite(out));
        // Absurd jitter and motion are bounded, not undefined.
        f.camera.jitter = glm::vec2(1e30f, -kInf);
        f.motion.assign(c.w, c.h, glm::vec2(-1e30f, 1e20f));
        upsampler.upsample(low.view(), {1e30f, kNaN}, f, out.view());
        upsampler.upsample(low.view(), {-1e30f, 5.0f}, f, out.view());
        ASSERT_TRUE(all_finite(out));
    }
}

}  // namespace
}  // namespace reprise
