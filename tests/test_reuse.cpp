// Shading reuse in the heavy renderer: what may never be reused (disocclusions, camera cuts),
// refresh periods, convergence of a still scene, and error bounds on the heavy scenes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "reprise/core/metrics.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "support/renderer.hpp"

using namespace reprise;
using namespace reprise::server;

namespace {

using reprise::test::shared_renderer;

constexpr int kWidth = 128, kHeight = 72;
constexpr double kFps = 30.0;
constexpr float kT = 8.0f / 255.0f;

RenderSettings heavy(ReuseSettings reuse = {}) {
    return {.width = kWidth, .height = kHeight, .shading = Shading::Heavy, .reuse = reuse};
}

void load(const std::string& name, Scene& scene, CameraPath& path) {
    ASSERT_TRUE(load_scene(name, scene, path).ok()) << name;
}

// Fraction of pixels where a display channel differs by more than T, and the largest difference.
struct DisplayError {
    double above = 0.0;
    float max = 0.0f;
};
DisplayError display_error(const Frame& a, const Frame& b) {
    Image<glm::vec3> da(kWidth, kHeight), db(kWidth, kHeight);
    to_display(a.color.view(), da.view());
    to_display(b.color.view(), db.view());
    DisplayError e;
    std::size_t above = 0;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            glm::vec3 d = glm::abs(da(x, y) - db(x, y));
            float m = std::max(d.x, std::max(d.y, d.z));
            e.max = std::max(e.max, m);
            above += m > kT;
        }
    e.above = double(above) / double(kWidth * kHeight);
    return e;
}

TEST(Reuse, NewlyVisiblePixelsAreMisses) {
    Renderer& r = shared_renderer();
    Scene scene;
    CameraPath path;
    load("courtyard", scene, path);
    r.drop_reuse_cache();
    const RenderSettings settings = heavy({.mode = Reuse::Cache, .period = 255});
    Frame before, now;
    int disoccluded = 0;
    for (int f = 0; f < 8; ++f) {
        std::swap(before, now);
        ASSERT_TRUE(r.render_frame(scene, path, f, kFps, settings, now).ok());
        if (f == 0) continue;
        const ReuseMaps& maps = r.reuse_maps();
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x) {
                if (now.id(x, y) == 0) continue;
                // Where this surface point was: another object (or nothing) covered it then.
                const glm::vec2 m = now.motion(x, y);
                const int px = int(std::floor(x + 0.5f + m.x)),
                          py = int(std::floor(y + 0.5f + m.y));
                const bool outside = !(px >= 0 && py >= 0 && px < kWidth && py < kHeight);
                if (!outside && before.id(px, py) == now.id(x, y)) continue;
                ++disoccluded;
                EXPECT_EQ(maps.status(x, y), kReuseMiss)
                    << "frame " << f << " pixel " << x << "," << y;
            }
        EXPECT_GT(r.reuse_stats().reused, r.reuse_stats().covered / 2) << "frame " << f;
    }
    EXPECT_GT(disoccluded, 20);  // the moving objects uncover something
}

TEST(Reuse, NothingReusedAcrossACameraCut) {
    Renderer& r = shared_renderer();
    Scene scene;
    CameraPath path;
    load("cut", scene, path);  // cut at 0.5 s: between frames 14 and 15 at 30 Hz
    r.drop_reuse_cache();
    const RenderSettings settings = heavy({.mode = Reuse::Cache, .period = 255});
    Frame frame;
    for (int f = 12; f <= 16; ++f) {
        ASSERT_TRUE(r.render_frame(scene, path, f, kFps, settings, frame).ok());
        const ReuseStats& s = r.reuse_stats();
        if (f == 15) {
            EXPECT_EQ(s.hits, 0);
            EXPECT_EQ(s.shaded, s.covered);
        } else if (f > 12) {
            EXPECT_GT(s.hit_rate(), 0.5) << "frame " << f;
        }
    }
    // A `previous` instant that is not the frame rendered last is a cut as well.
    Instant now = instant_on_path(path, scene, 20 / kFps, kWidth, kHeight);
    Instant elsewhere = instant_on_path(path, scene, 3 / kFps, kWidth, kHeight);
    ASSERT_TRUE(r.render(scene, now, elsewhere, settings, frame).ok());
    EXPECT_EQ(r.reuse_stats().hits, 0);
}

TEST(Reuse, EveryPixelIsReshadedWithinItsPeriod) {
    Renderer& r = shared_renderer();
    Scene scene;
    CameraPath path;
    load("stroll", scene, path);  // moving camera: screen-space patterns alone would not do
    Frame frame;
    for (Refresh kind : {Refresh::Tiled, Refresh::Random, Refresh::Blocks, Refresh::Interleaved})
        for (int period : {3, 4}) {
            r.drop_reuse_cache();
            const RenderSettings settings =
                heavy({.mode = Reuse::Cache, .refresh = kind, .period = period});
            int64_t reused = 0;
            for (int f = 0; f < 2 * period + 2; ++f) {
                ASSERT_TRUE(r.render_frame(scene, path, f, kFps, settings, frame).ok());
                const ReuseMaps& maps = r.reuse_maps();
                const uint8_t oldest =
                    *std::max_element(maps.age.data(), maps.age.data() + maps.age.pixel_count());
                EXPECT_LT(int(oldest), period)
                    << to_string(kind) << ":" << period << " frame " << f;
                reused += r.reuse_stats().reused;
            }
            EXPECT_GT(reused, 0) << to_string(kind);
        }
    // Adaptive reshading keeps its cap too.
    r.drop_reuse_cache();
    for (int f = 0; f < 10; ++f) {
        ASSERT_TRUE(r.render_frame(scene, path, f, kFps,
                                   heavy({.mode = Reuse::Adaptive, .period = 5}), frame)
                        .ok());
        const ReuseMaps& maps = r.reuse_maps();
        EXPECT_LT(int(*std::max_element(maps.age.data(), maps.age.data() + maps.age.pixel_count())),
                  5);
    }
}

TEST(Reuse, AStillSceneConvergesToFullShading) {
    Renderer& r = shared_renderer();
    Scene scene;
    CameraPath path;
    load("courtyard", scene, path);
    const Instant still = instant_on_path(path, scene, 0.4, kWidth, kHeight);
    Frame full, reused;
    ASSERT_TRUE(r.render(scene, still, still, heavy(), full).ok());
    for (Reuse mode : {Reuse::Cache, Reuse::Adaptive}) {
        r.drop_reuse_cache();
        const RenderSettings settings = heavy({.mode = mode, .period = 6});
        for (int f = 0; f < 8; ++f)
            ASSERT_TRUE(r.render(scene, still, still, settings, reused).ok());
        EXPECT_GT(r.reuse_stats().hit_rate(), 0.99);
        EXPECT_LT(r.reuse_stats().shaded_fraction(), 0.5);  // it reuses, and still matches:
        const DisplayError e = display_error(full, reused);
        EXPECT_EQ(e.above, 0.0);
        EXPECT_LE(e.max, 2.0f / 255.0f);
    }
}

// Mean fraction of pixels above T over frames 1..n-1 of a scene with `reuse`, against full shading.
double mean_above(const std::string& name, ReuseSettings reuse, int frames, double& shaded) {
    Renderer& r = shared_renderer();
    Scene scene;
    CameraPath path;
    EXPECT_TRUE(load_scene(name, scene, path).ok());
    r.drop_reuse_cache();
    Frame full, reused;
    double above = 0.0;
    shaded = 0.0;
    for (int f = 0; f < frames; ++f) {
        EXPECT_TRUE(r.render_frame(scene, path, f, kFps, heavy(), full).ok());
        EXPECT_TRUE(r.render_frame(scene, path, f, kFps, heavy(reuse), reused).ok());
        if (f == 0) continue;
        above += display_error(full, reused).above;
        shaded += r.reuse_stats().shaded_fraction();
    }
    shaded /= frames - 1;
    return above / (frames - 1);
}

TEST(Reuse, ErrorStaysBoundedOnTheHeavyScenes) {
    for (const char* name : {"courtyard", "stroll"}) {
        double shaded = 0.0;
        const double uniform = mean_above(
            name, {.mode = Reuse::Cache, .refresh = Refresh::Blocks, .period = 4}, 10, shaded);
        std::printf("%s blocks:4: %.3f %% above T, %.1f %% shaded\n", name, 100 * uniform,
                    100 * shaded);
        EXPECT_LE(uniform, 0.01) << name << ": blocks:4";  // measured 0.5 % at 128x72
        EXPECT_LT(shaded, 0.45) << name;
        const double adaptive =
            mean_above(name, {.mode = Reuse::Adaptive, .period = 16}, 10, shaded);
        std::printf("%s adaptive: %.3f %% above T, %.1f %% shaded\n", name, 100 * adaptive,
                    100 * shaded);
        EXPECT_LE(adaptive, 0.005) << name << ": adaptive";  // measured 0.1 %
        EXPECT_LT(shaded, 0.65) << name;
    }
}

TEST(Reuse, BadSettingsAreStatuses) {
    Renderer& r = shared_renderer();
    Scene scene;
    CameraPath path;
    load("courtyard", scene, path);
    Frame frame;
    EXPECT_FALSE(
        r.render_frame(scene, path, 0, kFps, heavy({.mode = Reuse::Cache, .period = 0}), frame)
            .ok());
    EXPECT_FALSE(r.render_frame(scene, path, 0, kFps,
                                heavy({.mode = Reuse::Adaptive, .threshold = -1.0f}), frame)
                     .ok());
    EXPECT_FALSE(
        r.render_frame(scene, path, 0, kFps, heavy({.mode = Reuse::Cache, .smoothing = NAN}), frame)
            .ok());
    ReuseSettings reuse;
    EXPECT_TRUE(parse_refresh("tiled:8", reuse).ok());
    EXPECT_EQ(reuse.refresh, Refresh::Tiled);
    EXPECT_EQ(reuse.period, 8);
    for (const char* bad : {"", "tiles:4", "random:0", "random:256", "blocks:4x", "interleaved:"})
        EXPECT_FALSE(parse_refresh(bad, reuse).ok()) << bad;
}

}  // namespace
