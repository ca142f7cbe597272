// Camera fit: the relative pose recovered from depth and motion of rendered scenes, what it saves
// in a stream whose frames carry no camera, decoder agreement, degenerate inputs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "../codec/src/camera_fit.hpp"
#include "reprise/codec/codec.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "support/codec.hpp"
#include "support/frames.hpp"
#include "support/renderer.hpp"

using namespace reprise;
using namespace reprise::codec;

namespace {

using test::kInf;
using test::kNaN;
using test::same_bits;

std::vector<Frame> render(const std::string& scene_name, int frames, int w, int h) {
    return test::render_scene(scene_name, frames, w, h);
}

std::vector<Frame> without_cameras(std::vector<Frame> frames) {
    for (Frame& f : frames) {
        const double time = f.camera.time;
        f.camera = Camera{};
        f.camera.time = time;
    }
    return frames;
}

// This camera space -> the previous one's, as the renderer's cameras give it.
glm::dmat4 true_relative(const Camera& c) {
    return glm::dmat4(c.prev_view) * glm::inverse(glm::dmat4(c.view));
}

// The angle between two rotations, from the Frobenius norm of their difference (acos of the
// trace loses precision at small angles).
double angle_deg(const glm::dmat4& a, const glm::dmat4& b) {
    double sum = 0.0;
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) sum += (a[c][r] - b[c][r]) * (a[c][r] - b[c][r]);
    return glm::degrees(2.0 * std::asin(std::min(1.0, std::sqrt(sum / 8.0))));
}

double translation_error(const glm::dmat4& a, const glm::dmat4& b) {
    return glm::length(glm::dvec3(a[3]) - glm::dvec3(b[3]));
}

bool finite(const glm::dmat4& m) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r])) return false;
    return true;
}

using test::Coded;
using test::encode_all;

}  // namespace

// With the renderer's lens the fit recovers the camera's motion between frames: `fast` pans
// sideways past a ball moving 40 px a frame (an outlier), `fence` orbits (rotation and
// translation).
TEST(CameraFit, RecoversTheRelativePose) {
    for (const char* scene : {"fast", "fence"}) {
        const auto frames = render(scene, 4, 320, 192);
        for (std::size_t i = 1; i < frames.size(); ++i) {
            const Frame& f = frames[i];
            const CameraFit fit =
                fit_camera(f.depth.view(), f.motion.view(), f.camera.projection, false);
            ASSERT_TRUE(fit.ok) << scene << " frame " << i;
            const glm::dmat4 truth = true_relative(f.camera);
            const double travel = glm::length(glm::dvec3(truth[3]));
            std::printf(
                "%s %zu: angle error %.6f deg (of %.4f), translation error %.6f of %.5f, "
                "%d of %d inliers, rms %.4f px\n",
                scene, i, angle_deg(fit.relative, truth), angle_deg(truth, glm::dmat4(1.0)),
                translation_error(fit.relative, truth), travel, fit.inliers, fit.samples,
                fit.rms_px);
            EXPECT_LT(angle_deg(fit.relative, truth), 0.01) << scene << " frame " << i;
            EXPECT_LT(translation_error(fit.relative, truth), 0.01 * travel + 1e-4)
                << scene << " frame " << i;
            EXPECT_LT(fit.rms_px, 0.1);
        }
    }
}

// Without a lens the fit also measures the focal length from how the orbit's rotation (0.48
// degrees a frame) bends the motion: from a lens 15 degrees too wide or too narrow.
TEST(CameraFit, MeasuresTheFocalLengthUnderRotation) {
    const auto frames = render("fence", 3, 320, 192);
    const Frame& f = frames[2];
    const double truth = f.camera.projection[1][1];
    for (double fov : {35.0, 65.0}) {
        const glm::mat4 start(glm::perspective(glm::radians(fov), 320.0 / 192.0, 0.1, 1000.0));
        const CameraFit fit = fit_camera(f.depth.view(), f.motion.view(), start, true);
        ASSERT_TRUE(fit.ok);
        const double focal = fit.projection[1][1];
        std::printf(
            "from %.0f degrees: focal %.5f (true %.5f), angle error %.5f deg, rms %.4f px\n", fov,
            focal, truth, angle_deg(fit.relative, true_relative(f.camera)), fit.rms_px);
        EXPECT_NEAR(focal / truth, 1.0, 0.01) << fov;
        EXPECT_LT(angle_deg(fit.relative, true_relative(f.camera)), 0.01) << fov;
    }
}

// Frames whose cameras were removed: the encoder fits one per frame, the motion section shrinks
// (measured: to 0.561 of the bits without the fit on fast, whose ball keeps its own motion, and
// 0.001 on fence) and the decoder gives the encoder's pictures (the fitted camera included).
TEST(CameraFit, StreamWithoutCamerasSendsLessMotion) {
    for (auto [scene, ratio] : {std::pair{"fast", 0.65}, std::pair{"fence", 0.01}}) {
        const auto rendered = render(scene, 6, 320, 192);
        const auto frames = without_cameras(rendered);
        EncoderOptions with{.qp = 30, .depth = DepthMode::View}, without = with;
        without.fit_cameras = false;
        const Coded fitted = encode_all(frames, with);
        const Coded plain = encode_all(frames, without);
        const Coded real = encode_all(rendered, with);
        std::printf(
            "%s: motion %zu bits with the fit, %zu without (%.3f), %zu with the "
            "renderer's cameras; total %zu / %zu / %zu; %zu cameras fitted, %zu key\n",
            scene, fitted.stats.motion_bits, plain.stats.motion_bits,
            double(fitted.stats.motion_bits) / double(plain.stats.motion_bits),
            real.stats.motion_bits, fitted.stats.total_bits(), plain.stats.total_bits(),
            real.stats.total_bits(), fitted.stats.cameras_fitted, fitted.stats.key_frames);
        EXPECT_EQ(plain.stats.cameras_fitted, 0u);
        EXPECT_EQ(real.stats.cameras_fitted, 0u);
        EXPECT_EQ(fitted.stats.cameras_fitted, frames.size());
        EXPECT_LE(double(fitted.stats.motion_bits), ratio * double(plain.stats.motion_bits));
        // As cheap as the renderer's own cameras (measured: the same bits on both scenes).
        EXPECT_LE(double(fitted.stats.motion_bits), 1.05 * double(real.stats.motion_bits) + 64);

        Decoder decoder;
        std::size_t n = 0;
        for (const Packet& p : fitted.packets) {
            ASSERT_TRUE(decoder.send_packet(p.data).ok());
            Frame d;
            while (decoder.receive_frame(d) == Result::Ok) {
                ASSERT_LT(n, frames.size());
                const Frame& e = fitted.reconstructions[n];
                EXPECT_TRUE(same_bits(d.color, e.color)) << scene << " frame " << n;
                EXPECT_TRUE(same_bits(d.depth, e.depth)) << scene << " frame " << n;
                EXPECT_TRUE(same_bits(d.motion, e.motion)) << scene << " frame " << n;
                EXPECT_TRUE(d.camera.view == e.camera.view &&
                            d.camera.prev_view == e.camera.prev_view &&
                            d.camera.projection == e.camera.projection);
                EXPECT_TRUE(has_projection(d.camera));
                // Chained: each frame's previous view is the view of the frame before.
                if (n > 0) {
                    EXPECT_TRUE(e.camera.prev_view == fitted.reconstructions[n - 1].camera.view);
                }
                ++n;
            }
        }
        EXPECT_EQ(n, frames.size());
    }
}

// Nothing to fit: no fit (identity), never NaN, and the encoder codes such frames.
TEST(CameraFit, DegenerateInputs) {
    const glm::mat4 lens = assumed_projection(64, 48);
    auto check = [&](const Image<float>& depth, const Image<glm::vec2>& motion, bool focal,
                     const char* what) {
        const CameraFit fit = fit_camera(depth.view(), motion.view(), lens, focal);
        EXPECT_TRUE(finite(fit.relative)) << what;
        EXPECT_TRUE(std::isfinite(fit.rms_px)) << what;
        EXPECT_TRUE(std::isfinite(fit.projection[0][0]) && std::isfinite(fit.projection[1][1]))
            << what;
        if (!fit.ok) {
            EXPECT_TRUE(fit.relative == glm::dmat4(1.0)) << what;
        }
        return fit;
    };
    for (bool focal : {false, true}) {
        Image<float> depth(64, 48, kInf);
        Image<glm::vec2> motion(64, 48, glm::vec2(0.0f));
        check(depth, motion, focal, "all background, still");
        depth.fill(3.0f);
        const CameraFit still = check(depth, motion, focal, "zero motion");
        EXPECT_LT(angle_deg(still.relative, glm::dmat4(1.0)), 1e-9);
        EXPECT_LT(glm::length(glm::dvec3(still.relative[3])), 1e-9);
        depth.fill(kNaN);
        motion.fill(glm::vec2(2.0f, 0.0f));
        EXPECT_FALSE(check(depth, motion, focal, "NaN depth").ok);
        depth.fill(2.0f);
        motion.fill(glm::vec2(kNaN));
        EXPECT_FALSE(check(depth, motion, focal, "NaN motion").ok);
        motion.fill(glm::vec2(1e30f, -1e30f));
        check(depth, motion, focal, "huge motion");
        Image<float> one(1, 1, 2.0f);
        Image<glm::vec2> one_motion(1, 1, glm::vec2(0.5f));
        EXPECT_FALSE(check(one, one_motion, focal, "1x1").ok);
        EXPECT_FALSE(fit_camera({}, {}, lens, focal).ok);
        EXPECT_FALSE(fit_camera(depth.view(), motion.view(), glm::mat4(1.0f), focal).ok);
    }
    for (int side : {1, 64}) {
        for (float z : {kInf, kNaN, 2.0f}) {
            Frame f;
            f.color = Image<glm::vec4>(side, side, glm::vec4(0.5f));
            f.depth = Image<float>(side, side, z);
            f.motion = Image<glm::vec2>(side, side, glm::vec2(0.0f));
            Encoder encoder;
            for (int i = 0; i < 2; ++i) {
                ASSERT_TRUE(encoder.send_frame(f).ok()) << side << " " << z;
                Packet p;
                ASSERT_EQ(encoder.receive_packet(p), Result::Ok);
                const Camera& c = encoder.reconstruction().camera;
                EXPECT_TRUE(finite(glm::dmat4(c.view)) && finite(glm::dmat4(c.projection)));
            }
        }
    }
}
