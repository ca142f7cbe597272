#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "fruc_stages.hpp"
#include "reprise/core/camera_math.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::warp {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

bool finite(glm::vec2 m) { return std::isfinite(m.x) && std::isfinite(m.y); }

// True when the camera alone explains the motion of pixel p (its surface point, seen through the
// previous camera, lands within the tolerance of where its motion says it was).
bool is_static(const StaticReprojection& to_previous, const glm::vec4& point, glm::vec2 p,
               glm::vec2 motion, float tolerance2) {
    glm::vec2 before;
    if (!finite(motion) || !to_previous.land(point, before)) return false;
    const glm::vec2 error = before - p - motion;
    return glm::dot(error, error) <= tolerance2;
}

}  // namespace

std::size_t motion_toward(const GBufferView& f, const Camera& to, float factor,
                          ImageView<const glm::vec2> inverted, float tolerance,
                          ImageView<glm::vec2> out) {
    const int w = f.width(), h = f.height();
    const StaticReprojection to_previous = camera_only_motion(f.camera, w, h);
    const StaticReprojection to_instant(f.camera, to.view, to.projection, w, h);
    const Unprojector& unproject = to_previous.unprojector();
    const float tolerance2 = tolerance * tolerance;
    std::atomic<std::size_t> moving{0};
    parallel_for(0, h, [&](int y0, int y1) {
        std::size_t local = 0;
        for (int y = y0; y < y1; ++y) {
            const float* z = f.depth.row(y);
            const glm::vec2* m = f.motion.row(y);
            glm::vec2* o = out.row(y);
            for (int x = 0; x < w; ++x) {
                const glm::vec2 p(float(x) + 0.5f, float(y) + 0.5f);
                o[x] = m[x];
                if (std::isnan(z[x])) continue;
                const glm::vec4 point = unproject.point(p.x, p.y, z[x]);
                glm::vec2 landed;
                if (is_static(to_previous, point, p, m[x], tolerance2)) {
                    if (to_instant.land(point, landed)) o[x] = (landed - p) / factor;
                    continue;
                }
                ++local;
                if (!inverted.empty() && finite(inverted(x, y))) o[x] = inverted(x, y);
            }
        }
        moving += local;
    });
    return moving.load();
}

void invert_motion(const GBufferView& b, float tolerance, Image<glm::vec2>& inverted,
                   Image<float>& depth) {
    const int w = b.width(), h = b.height();
    inverted.assign(w, h, glm::vec2(std::numeric_limits<float>::quiet_NaN()));
    depth.assign(w, h, kInf);
    const StaticReprojection to_previous = camera_only_motion(b.camera, w, h);
    const Unprojector& unproject = to_previous.unprojector();
    const float tolerance2 = tolerance * tolerance;
    // Serial: the moving pixels are usually few, and the nearest must win where two land.
    for (int y = 0; y < h; ++y) {
        const float* z = b.depth.row(y);
        const glm::vec2* m = b.motion.row(y);
        for (int x = 0; x < w; ++x) {
            const glm::vec2 q(float(x) + 0.5f, float(y) + 0.5f);
            if (!(z[x] < kInf) || !finite(m[x])) continue;
            if (is_static(to_previous, unproject.point(q.x, q.y, z[x]), q, m[x], tolerance2)) continue;
            // The 2x2 pixels whose centres surround where q was: an object that grows leaves
            // no gaps at one pixel per step.
            const glm::vec2 p = q + m[x] - 0.5f;
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
