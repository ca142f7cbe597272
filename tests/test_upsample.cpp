// Spatio-temporal upsampling (warp/upsample.hpp) and the renderer's low-resolution jittered colour.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "reprise/core/exr.hpp"
#include "reprise/core/metrics.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/warp/upsample.hpp"
#include "support/frames.hpp"
#include "support/renderer.hpp"

namespace reprise {
namespace {

using test::display_psnr;
using test::shared_renderer;

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
        .width = width, .height = height, .shading = unlit ? server::Shading::Unlit : server::Shading::Lit};
    r.full.resize(frames);
    r.low.resize(frames);
    r.jitter.resize(frames);
    for (int i = 0; i < frames; ++i) {
        status = shared_renderer().render_frame_lowres(scene, path, i, 30.0, settings, factor, r.full[i],
                                                       r.low[i], r.jitter[i]);
        EXPECT_TRUE(status.ok()) << status.message();
    }
    return r;
}

TEST(LowresRender, SamplesLandOnFullResolutionPixelCentres) {
    const Rendered r = render_lowres("pan", "static", 4, 64, 36, 4, true);
    for (int i = 0; i < 4; ++i) {
        ASSERT_EQ(r.low[i].width(), 32);
        ASSERT_EQ(r.low[i].height(), 18);
        const glm::vec2 j = r.jitter[i];
        int same = 0, count = 0;
        for (int v = 0; v < 18; ++v) {
            for (int u = 0; u < 32; ++u) {
                const int x = int(std::floor((u + 0.5f) * 2.0f + j.x)), y = int(std::floor((v + 0.5f) * 2.0f + j.y));
                const glm::vec4 a = r.low[i](u, v), b = r.full[i].color(x, y);
                same += std::abs(a.x - b.x) + std::abs(a.y - b.y) + std::abs(a.z - b.z) < 0.02f;
                ++count;
            }
        }
        EXPECT_GT(same, count * 95 / 100) << "frame " << i << " jitter " << j.x << "," << j.y;
        for (int oy = -1; oy <= 1; ++oy) for (int ox = -1; ox <= 1; ++ox) {
            int s2 = 0; double sad = 0;
            for (int v = 1; v < 17; ++v) for (int u = 1; u < 31; ++u) {
                const int x = int(std::floor((u + 0.5f) * 2.0f + j.x)) + ox, y = int(std::floor((v + 0.5f) * 2.0f + j.y)) + oy;
                const glm::vec4 a = r.low[i](u, v), b = r.full[i].color(x, y);
                s2 += std::abs(a.x - b.x) + std::abs(a.y - b.y) + std::abs(a.z - b.z) < 0.02f;
                sad += std::abs(a.x - b.x) + std::abs(a.y - b.y) + std::abs(a.z - b.z);
            }
            printf("off %d %d: %d %.4f\n", ox, oy, s2, sad / 480);
        }
    }
}

TEST(LowresRender, Oracle) {
    for (bool unlit : {true, false}) {
    const Rendered r = render_lowres("pan", "static", 4, 320, 180, 4, unlit);
    Image<glm::vec4> composed(320, 180);
    for (int i = 0; i < 4; ++i) {
        const glm::vec2 j = r.jitter[i];
        for (int v = 0; v < 90; ++v)
            for (int u = 0; u < 160; ++u) {
                const int x = int(std::floor((u + 0.5f) * 2.0f + j.x)), y = int(std::floor((v + 0.5f) * 2.0f + j.y));
                composed(x, y) = r.low[i](u, v);
            }
    }
    printf("oracle unlit=%d psnr %.2f\n", unlit, display_psnr(r.full[3].color, composed));
    Image<glm::vec4> diff(320, 180);
    for (int y = 0; y < 180; ++y) for (int x = 0; x < 320; ++x) { glm::vec4 d = glm::abs(composed(x, y) - r.full[3].color(x, y)) * 4.0f; d.w = 1; diff(x, y) = d; }
    Frame a = r.full[3]; a.color = diff; (void)write_frame("/tmp/wt9u_diff.exr", a);
    a.color = composed; (void)write_frame("/tmp/wt9u_comp.exr", a);
    }
}

}  // namespace
}  // namespace reprise
