// The shared camera math: unprojection round trips for every kind of projection, landing in
// another camera, camera-only motion.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "reprise/core/camera_math.hpp"

using namespace reprise;

namespace {

constexpr int kW = 320, kH = 200;

// Pixel positions and depths spread over the image and the depth range.
void round_trip(const glm::mat4& projection, bool expect_axis_aligned, float depth_lo,
                float depth_hi) {
    const Unprojector unproject(projection, kW, kH);
    EXPECT_EQ(unproject.axis_aligned(), expect_axis_aligned);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> ux(0.0f, float(kW)), uy(0.0f, float(kH)),
        ud(depth_lo, depth_hi);
    for (int i = 0; i < 500; ++i) {
        const float px = ux(rng), py = uy(rng), depth = ud(rng);
        const glm::vec4 point = unproject.point(px, py, depth);
        ASSERT_NEAR(-point.z / point.w, depth, 1e-4f * depth);
        glm::vec2 pixel;
        ASSERT_TRUE(clip_to_pixel(projection * point, kW, kH, pixel));
        ASSERT_NEAR(pixel.x, px, 2e-3f) << i;
        ASSERT_NEAR(pixel.y, py, 2e-3f) << i;
    }
}

}  // namespace

TEST(CameraMath, UnprojectionRoundTripsForEveryProjection) {
    round_trip(glm::perspective(1.0f, float(kW) / kH, 0.1f, 100.0f), true, 0.2f, 90.0f);
    round_trip(glm::frustum(-0.03f, 0.05f, -0.02f, 0.04f, 0.1f, 100.0f), true, 0.2f,
               90.0f);  // off-centre
    round_trip(glm::ortho(-4.0f, 4.0f, -3.0f, 3.0f, 0.1f, 50.0f), true, 0.2f, 45.0f);
    glm::mat4 skewed = glm::perspective(1.0f, float(kW) / kH, 0.1f, 100.0f);
    skewed[1][0] = 0.3f;  // x depends on y: the 2x2 solve
    round_trip(skewed, false, 0.2f, 90.0f);
    glm::mat4 odd = glm::perspective(1.0f, float(kW) / kH, 0.1f, 100.0f);
    odd[0][3] = 0.05f;  // clip w depends on x: through the inverse matrix
    round_trip(odd, false, 0.5f, 20.0f);
}

TEST(CameraMath, BackgroundIsTheDirectionThroughThePixel) {
    const glm::mat4 p = glm::perspective(1.2f, float(kW) / kH, 0.1f, 100.0f);
    const Unprojector unproject(p, kW, kH);
    const glm::vec4 d = unproject.point(100.5f, 40.5f, INFINITY);
    EXPECT_EQ(d.w, 0.0f);
    EXPECT_EQ(d.z, -1.0f);
    glm::vec2 pixel;
    ASSERT_TRUE(clip_to_pixel(p * d, kW, kH, pixel));
    EXPECT_NEAR(pixel.x, 100.5f, 1e-3f);
    EXPECT_NEAR(pixel.y, 40.5f, 1e-3f);
    // Orthographic background lies on the far plane.
    const Unprojector ortho(glm::ortho(-4.0f, 4.0f, -3.0f, 3.0f, 0.1f, 50.0f), kW, kH, 50.0f);
    EXPECT_EQ(ortho.point(10.0f, 10.0f, INFINITY).z, -50.0f);
}

TEST(CameraMath, CameraOnlyMotionOfASidewaysPan) {
    // Camera 0.25 units to the right of where it was, plane at depth 5: content moved left by
    // f * 0.25 / 5 pixels, so backward motion is +that.
    Camera c;
    c.projection = glm::perspective(1.0f, float(kW) / kH, 0.1f, 100.0f);
    c.prev_view = glm::mat4(1.0f);
    c.view = glm::translate(glm::mat4(1.0f), glm::vec3(-0.25f, 0.0f, 0.0f));
    c.prev_projection = c.projection;
    const StaticReprojection motion = camera_only_motion(c, kW, kH);
    const float f = c.projection[0][0] * kW / 2.0f;
    for (float px : {0.5f, 160.5f, 319.5f}) {
        glm::vec2 before;
        ASSERT_TRUE(motion.land(px, 100.5f, 5.0f, before));
        EXPECT_NEAR(before.x - px, f * 0.25f / 5.0f, 1e-3f);
        EXPECT_NEAR(before.y - 100.5f, 0.0f, 1e-4f);
        EXPECT_NEAR(motion.target_depth(motion.unprojector().point(px, 100.5f, 5.0f)), 5.0f, 1e-5f);
        // The point at infinity does not move under a pure translation.
        ASSERT_TRUE(motion.land(px, 100.5f, INFINITY, before));
        EXPECT_NEAR(before.x, px, 1e-3f);
    }
    // Behind the other camera: no landing.
    Camera turned = c;
    turned.prev_view = glm::rotate(glm::mat4(1.0f), 3.14159f, glm::vec3(0, 1, 0));
    glm::vec2 unused;
    EXPECT_FALSE(camera_only_motion(turned, kW, kH).land(160.5f, 100.5f, 5.0f, unused));
}
