// Anti-aliased colour with an exact single-sample G-buffer: an edge pixel's colour blends its two
// surfaces by the covered fraction, while depth, motion, normal, id and coverage A are the pixel
// centre's single sample, bit for bit the same as without anti-aliasing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "support/renderer.hpp"

using namespace reprise;
using namespace reprise::server;

namespace {

using reprise::test::shared_renderer;

constexpr int kW = 64, kH = 48;
constexpr glm::vec3 kNear{0.9f, 0.2f, 0.1f}, kFar{0.1f, 0.3f, 0.8f};
constexpr float kNearZ = 5.0f, kFarZ = 8.0f;
// The near quad's right edge: x = kEdgeX + kEdgeSlope * y in pixels, sweeping one pixel over
// the height so that rows see every covered fraction.
constexpr float kEdgeX = 30.0f, kEdgeSlope = 1.0f / float(kH);

// Pixel (x, y) -> world (x, -y): an orthographic camera looking down -z, one unit per pixel.
Instant pixel_camera(float shift_x) {
    Instant at;
    at.view = glm::translate(glm::mat4(1.0f), glm::vec3(-shift_x, 0.0f, 0.0f));
    at.projection = glm::ortho(0.0f, float(kW), -float(kH), 0.0f, 0.5f, 20.0f);
    at.near = 0.5f;
    at.far = 20.0f;
    return at;
}

void add_quad(Scene& scene, const glm::vec3 corners[4], glm::vec3 color, uint32_t id) {
    Primitive p;
    for (int i = 0; i < 4; ++i) {
        p.positions.push_back(corners[i]);
        p.normals.push_back({0, 0, 1});
    }
    p.indices = {0, 1, 2, 0, 2, 3};
    p.material = int(scene.materials.size());
    scene.materials.push_back({.base_color = glm::vec4(color, 1.0f), .double_sided = true});
    scene.meshes.push_back({.name = "quad", .primitives = {p}});
    Node node;
    node.mesh = int(scene.meshes.size()) - 1;
    node.object_id = id;
    scene.nodes.push_back(node);
    scene.roots.push_back(int(scene.nodes.size()) - 1);
}

// A flat far quad filling the view (id 2) and a near quad (id 1) left of the slanted edge.
Scene edge_scene() {
    Scene scene;
    const float m = 16.0f;
    const glm::vec3 far[4] = {
        {-m, m, -kFarZ}, {kW + m, m, -kFarZ}, {kW + m, -kH - m, -kFarZ}, {-m, -kH - m, -kFarZ}};
    add_quad(scene, far, kFar, 2);
    const glm::vec3 near[4] = {{-m, m, -kNearZ},
                               {kEdgeX - kEdgeSlope * m, m, -kNearZ},
                               {kEdgeX + kEdgeSlope * (kH + m), -kH - m, -kNearZ},
                               {-m, -kH - m, -kNearZ}};
    add_quad(scene, near, kNear, 1);
    return scene;
}

// Area of pixel (x, y) left of the edge.
double near_fraction(int x, int y) {
    double area = 0.0;
    const int steps = 256;
    for (int s = 0; s < steps; ++s) {
        const double line = kEdgeX + kEdgeSlope * (y + (s + 0.5) / steps);
        area += std::clamp(line - x, 0.0, 1.0);
    }
    return area / steps;
}

Frame render_edge(int samples, AntiAliasing method = AntiAliasing::Auto) {
    const Scene scene = edge_scene();
    // The content moved 1.5 px left since `before`: motion (+1.5, 0).
    Instant now = pixel_camera(0.0f), before = pixel_camera(-1.5f);
    now.time = 1.0 / 30.0;
    Frame frame;
    Status status = shared_renderer().render(scene, now, before,
                                             {.width = kW,
                                              .height = kH,
                                              .shading = Shading::Unlit,
                                              .aa_samples = samples,
                                              .aa_method = method},
                                             frame);
    EXPECT_TRUE(status.ok()) << status.message();
    return frame;
}

struct AaCase {
    int samples;
    AntiAliasing method;
};
class EdgeAntiAliasing : public ::testing::TestWithParam<AaCase> {};

TEST_P(EdgeAntiAliasing, EdgePixelsBlendTheirTwoSurfacesByCoverage) {
    const int samples = GetParam().samples;
    const bool msaa =
        GetParam().method == AntiAliasing::Msaa ||
        (GetParam().method == AntiAliasing::Auto && shared_renderer().msaa_supported(samples));
    const Frame frame = render_edge(samples, GetParam().method);
    ASSERT_EQ(frame.width(), kW);
    int edge_pixels = 0;
    double worst = 0.0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const glm::vec3 c(frame.color(x, y));
            // The colour lies on the segment between the two surfaces' colours.
            const double t = (double(c.r) - kFar.r) / (double(kNear.r) - kFar.r);
            for (int k = 1; k < 3; ++k)
                ASSERT_NEAR(c[k], kFar[k] + t * (kNear[k] - kFar[k]), 1e-5)
                    << x << "," << y << " channel " << k;
            const double f = near_fraction(x, y);
            // A near-vertical edge through N samples spread evenly in x (the standard patterns):
            // the covered count misses the area by at most 1/(2N) plus the slope across a pixel.
            const double tolerance = 0.5 / samples + kEdgeSlope + 1e-4;
            worst = std::max(worst, std::abs(t - f));
            ASSERT_NEAR(t, f, tolerance) << x << "," << y;
            if (f > tolerance && f < 1.0 - tolerance) {
                ++edge_pixels;
                EXPECT_GT(t, 1e-3) << x << "," << y;
                EXPECT_LT(t, 1.0 - 1e-3) << x << "," << y;
            }
            // A multiple of 1/N: every sample is one surface or the other.
            EXPECT_NEAR(t * samples, std::round(t * samples), 1e-3) << x << "," << y;
        }
    EXPECT_GE(edge_pixels, int(0.8 * kH * (1.0 - 1.0 / samples - 2.0 * kEdgeSlope)));
    std::printf("[aa] %2d samples (%s): %d edge pixels, coverage within %.4f of the area\n",
                samples, msaa ? "MSAA" : "supersampling", edge_pixels, worst);
}

TEST_P(EdgeAntiAliasing, GBufferStaysTheSingleSampleAtThePixelCentre) {
    const Frame aa = render_edge(GetParam().samples, GetParam().method), single = render_edge(1);
    int near = 0, far = 0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            ASSERT_EQ(aa.depth(x, y), single.depth(x, y)) << x << "," << y;
            ASSERT_EQ(aa.id(x, y), single.id(x, y)) << x << "," << y;
            ASSERT_EQ(aa.normal(x, y), single.normal(x, y)) << x << "," << y;
            const glm::vec2 m = aa.motion(x, y), n = single.motion(x, y);
            ASSERT_TRUE(m == n) << x << "," << y;
            ASSERT_EQ(aa.color(x, y).a, single.color(x, y).a) << x << "," << y;
            // One surface's exact values: the one under the pixel centre.
            const bool centre_near = double(x) + 0.5 < kEdgeX + kEdgeSlope * (y + 0.5);
            if (std::abs(double(x) + 0.5 - (kEdgeX + kEdgeSlope * (y + 0.5))) < 1e-3) continue;
            ASSERT_EQ(aa.id(x, y), centre_near ? 1u : 2u) << x << "," << y;
            ASSERT_EQ(aa.depth(x, y), centre_near ? kNearZ : kFarZ) << x << "," << y;
            ASSERT_NEAR(m.x, 1.5f, 1e-4) << x << "," << y;
            ASSERT_EQ(m.y, 0.0f) << x << "," << y;
            ASSERT_EQ(aa.color(x, y).a, 1.0f);
            (centre_near ? near : far) += 1;
        }
    EXPECT_GT(near, kW * kH / 3);
    EXPECT_GT(far, kW * kH / 3);
}

// MSAA forced at 4x (llvmpipe's only count); Auto supersamples on llvmpipe.
INSTANTIATE_TEST_SUITE_P(Samples, EdgeAntiAliasing,
                         ::testing::Values(AaCase{2, AntiAliasing::Auto},
                                           AaCase{4, AntiAliasing::Auto},
                                           AaCase{4, AntiAliasing::Msaa},
                                           AaCase{16, AntiAliasing::Auto}));

TEST(AntiAliasing, OffGivesSingleSampleColorAndOnAgreesAwayFromEdges) {
    const Frame single = render_edge(1), aa = render_edge(4);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const glm::vec3 c(single.color(x, y));
            ASSERT_TRUE(c == kNear || c == kFar) << x << "," << y;  // no blends at all
            if (near_fraction(x, y) == 0.0 || near_fraction(x, y) == 1.0) {
                ASSERT_EQ(glm::vec3(aa.color(x, y)), c) << x << "," << y;
            }
        }
}

TEST(AntiAliasing, LitSceneKeepsItsGBufferAndSoftensOnlyEdges) {
    Scene scene;
    CameraPath path;
    ASSERT_TRUE(load_scene("fence", scene, path).ok());
    const int w = 160, h = 90;
    Frame single, aa;
    ASSERT_TRUE(
        shared_renderer()
            .render_frame(scene, path, 5, 30.0, {.width = w, .height = h, .aa_samples = 1}, single)
            .ok());
    ASSERT_TRUE(
        shared_renderer().render_frame(scene, path, 5, 30.0, {.width = w, .height = h}, aa).ok());
    int changed = 0, changed_at_edges = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            ASSERT_EQ(aa.depth(x, y), single.depth(x, y));
            ASSERT_EQ(aa.id(x, y), single.id(x, y));
            ASSERT_EQ(aa.color(x, y).a, single.color(x, y).a);
            const glm::vec2 m = aa.motion(x, y), n = single.motion(x, y);
            ASSERT_TRUE(m == n || (std::isnan(m.x) && std::isnan(n.x)));
            const glm::vec3 d = glm::abs(glm::vec3(aa.color(x, y) - single.color(x, y)));
            if (std::max({d.r, d.g, d.b}) < 1e-3f) continue;
            ++changed;
            bool edge = false;
            for (int j = std::max(y - 1, 0); j <= std::min(y + 1, h - 1); ++j)
                for (int i = std::max(x - 1, 0); i <= std::min(x + 1, w - 1); ++i)
                    edge |= single.id(i, j) != single.id(x, y);
            changed_at_edges += edge;
        }
    EXPECT_GT(changed, w * h / 100);  // the fence's rails and posts are anti-aliased
    std::printf("[aa] fence: %d pixels changed, %d of them next to another object\n", changed,
                changed_at_edges);
}

TEST(AntiAliasing, HeavyShadingAndLowResolutionRendersStaySingleSample) {
    Scene scene;
    CameraPath path;
    ASSERT_TRUE(load_scene("courtyard", scene, path).ok());
    const RenderSettings heavy{.width = 64, .height = 36, .shading = Shading::Heavy};
    RenderSettings heavy_single = heavy;
    heavy_single.aa_samples = 1;
    Frame a, b;
    ASSERT_TRUE(shared_renderer().render_frame(scene, path, 2, 30.0, heavy, a).ok());
    ASSERT_TRUE(shared_renderer().render_frame(scene, path, 2, 30.0, heavy_single, b).ok());
    for (int i = 0; i < 64 * 36; ++i) ASSERT_EQ(a.color.data()[i], b.color.data()[i]);

    ASSERT_TRUE(load_scene("pan", scene, path).ok());
    Image<glm::vec4> low_aa, low_single;
    glm::vec2 jitter_aa, jitter_single;
    ASSERT_TRUE(shared_renderer()
                    .render_frame_lowres(scene, path, 3, 30.0, {.width = 64, .height = 36}, 4, a,
                                         low_aa, jitter_aa)
                    .ok());
    ASSERT_TRUE(shared_renderer()
                    .render_frame_lowres(scene, path, 3, 30.0,
                                         {.width = 64, .height = 36, .aa_samples = 1}, 4, b,
                                         low_single, jitter_single)
                    .ok());
    ASSERT_EQ(jitter_aa, jitter_single);
    for (int i = 0; i < 64 * 36; ++i) ASSERT_EQ(a.color.data()[i], b.color.data()[i]);
    for (int i = 0; i < low_aa.width() * low_aa.height(); ++i)
        ASSERT_EQ(low_aa.data()[i], low_single.data()[i]);
}

TEST(AntiAliasing, RejectsUnsupportedSampleCounts) {
    Scene scene = edge_scene();
    Frame frame;
    for (int samples : {0, 3, 32, -4}) {
        Status status =
            shared_renderer().render(scene, pixel_camera(0), pixel_camera(0),
                                     {.width = 16, .height = 16, .aa_samples = samples}, frame);
        EXPECT_FALSE(status.ok()) << samples;
        EXPECT_NE(status.message().find("anti-aliasing"), std::string::npos);
    }
}

}  // namespace
