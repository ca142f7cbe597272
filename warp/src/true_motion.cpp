#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "fruc_stages.hpp"
#include "reprise/core/camera_math.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/warp/true_motion.hpp"

namespace reprise::warp {

namespace {

bool finite(glm::vec2 m) { return std::isfinite(m.x) && std::isfinite(m.y); }

}  // namespace

namespace {

// The survey over the sampled pixels: sample(x, y, z, m) gives the depth and motion at (x, y).
template <class Sample>
bool linear_survey(const Camera& camera, int w, int h, const Sample& sample, const Camera& to,
                   float factor, float tolerance) {
    constexpr int kStep = kLinearSurveyStep;
    constexpr float kDeviation = 0.02f;  // px between the true and the linear landing
    const StaticReprojection to_previous = camera_only_motion(camera, w, h);
    const StaticReprojection to_instant(camera, to.view, to.projection, w, h);
    const Unprojector& unproject = to_previous.unprojector();
    std::atomic<bool> linear{true};
    const int rows = (h + kStep / 2) / kStep;  // sampled rows kStep/2, kStep/2 + kStep, ...
    parallel_for(
        0, rows,
        [&](int r0, int r1) {
            for (int y = r0 * kStep + kStep / 2; y < std::min(h, r1 * kStep + kStep / 2);
                 y += kStep) {
                if (!linear.load(std::memory_order_relaxed)) return;
                for (int x = kStep / 2; x < w; x += kStep) {
                    float z;
                    glm::vec2 m;
                    sample(x, y, z, m);
                    const glm::vec2 p(float(x) + 0.5f, float(y) + 0.5f);
                    if (std::isnan(z)) continue;
                    const glm::vec4 point = unproject.point(p.x, p.y, z);
                    glm::vec2 before, landed;
                    if (!finite(m) || !to_previous.land(point, before) ||
                        !to_instant.land(point, landed))
                        return linear.store(false);
                    const glm::vec2 unexplained = before - p - m,
                                    off_line = landed - (p + factor * m);
                    if (glm::dot(unexplained, unexplained) > tolerance * tolerance ||
                        glm::dot(off_line, off_line) > kDeviation * kDeviation)
                        return linear.store(false);
                }
            }
        },
        8);
    return linear.load();
}

}  // namespace

bool motion_is_linear(const GBufferView& f, const Camera& to, float factor, float tolerance) {
    return linear_survey(
        f.camera, f.width(), f.height(),
        [&](int x, int y, float& z, glm::vec2& m) {
            z = f.depth(x, y);
            m = f.motion(x, y);
        },
        to, factor, tolerance);
}

bool motion_is_linear(const Camera& camera, int width, int height,
                      ImageView<const glm::vec4> samples, const Camera& to, float factor,
                      float tolerance) {
    constexpr int kStep = kLinearSurveyStep;
    REPRISE_ASSERT(samples.width == linear_survey_samples(width) &&
                   samples.height == linear_survey_samples(height));
    return linear_survey(
        camera, width, height,
        [&](int x, int y, float& z, glm::vec2& m) {
            const glm::vec4 v = samples(x / kStep, y / kStep);
            z = v.x;
            m = {v.y, v.z};
        },
        to, factor, tolerance);
}

std::size_t motion_toward(const GBufferView& f, const Camera& to, float factor,
                          ImageView<const glm::vec2> inverted, float tolerance,
                          Image<float>& static_depth, ImageView<glm::vec2> out) {
    const int w = f.width(), h = f.height();
    static_depth.resize(w, h);
    // Static pixels get their displacement to `to` in `out`, the others NaN (and NaN depth).
    const std::size_t moving =
        static_layer(f, to.view, to.projection, tolerance, static_depth.view(), out);
    const float per_factor = 1.0f / factor;
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float* z = static_depth.data() + std::size_t(y) * w;
            const glm::vec2* m = f.motion.row(y);
            glm::vec2* o = out.row(y);
            for (int x = 0; x < w; ++x) {
                if (!std::isnan(z[x]))
                    o[x] *= per_factor;
                else
                    o[x] = !inverted.empty() && finite(inverted(x, y)) ? inverted(x, y) : m[x];
            }
        }
    });
    return moving;
}

void invert_motion(const GBufferView& b, float tolerance, Image<float>& static_depth,
                   Image<glm::vec2>& inverted, Image<float>& depth) {
    const int w = b.width(), h = b.height();
    constexpr float kInf = std::numeric_limits<float>::infinity();
    inverted.resize(w, h);
    static_depth.resize(w, h);
    // Which pixels the camera explains (`inverted` holds the unused displacements meanwhile).
    std::size_t moving = std::size_t(w) * std::size_t(h);
    if (has_projection(b.camera))
        moving = static_layer(b, b.camera.view, b.camera.projection, tolerance, static_depth.view(),
                              inverted.view());
    else
        static_depth.fill(std::numeric_limits<float>::quiet_NaN());
    inverted.fill(glm::vec2(std::numeric_limits<float>::quiet_NaN()));
    if (moving == 0) return;
    depth.assign(w, h, kInf);
    // Serial: the nearest must win where two land; only the moving pixels are splatted.
    for (int y = 0; y < h; ++y) {
        const float* z = b.depth.row(y);
        const float* still = static_depth.data() + std::size_t(y) * w;
        const glm::vec2* m = b.motion.row(y);
        for (int x = 0; x < w; ++x) {
            if (!std::isnan(still[x]) || !(z[x] < kInf) || !finite(m[x])) continue;
            // The 2x2 pixels whose centres surround where the pixel was: an object that grows
            // leaves no gaps at one pixel per step.
            const glm::vec2 p = glm::vec2(float(x) + 0.5f, float(y) + 0.5f) + m[x] - 0.5f;
            if (!(p.x > -1.0f && p.y > -1.0f && p.x < float(w) && p.y < float(h))) continue;
            const int x0 = int(std::floor(p.x)), y0 = int(std::floor(p.y));
            for (int py = std::max(y0, 0); py <= std::min(y0 + 1, h - 1); ++py)
                for (int px = std::max(x0, 0); px <= std::min(x0 + 1, w - 1); ++px)
                    if (z[x] < depth(px, py)) {
                        depth(px, py) = z[x];
                        inverted(px, py) = m[x];
                    }
        }
    }
}

}  // namespace reprise::warp
