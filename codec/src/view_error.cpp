// The reprojection error that decoded depth causes, for DepthMode::View's bound (bench, tests).
#include <algorithm>
#include <cmath>

#include "internal.hpp"

namespace reprise::codec {

ViewDepthError measure_view_depth_error(const Camera& camera, ImageView<const float> truth,
                                        ImageView<const float> decoded, float displacement,
                                        float bound_px) {
    const glm::mat4& p = camera.projection;
    const double sx = p[0][0], sy = p[1][1], ox = p[2][0], oy = p[2][1];
    const int w = truth.width, h = truth.height;
    const double fx = sx * w / 2.0, fy = sy * h / 2.0, b = displacement;
    std::vector<glm::dvec3> cube;
    for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j)
            for (int k = -1; k <= 1; ++k)
                if (i || j || k) cube.push_back(b * glm::normalize(glm::dvec3(i, j, k)));
    ViewDepthError result;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float zt = truth(x, y), zd = decoded(x, y);
            const bool inf_t = zt == INFINITY, inf_d = zd == INFINITY;
            if (inf_t != inf_d) ++result.background_mismatches;
            if (!(zt > 0.0f && zd > 0.0f && std::isfinite(zt) && std::isfinite(zd))) continue;
            ++result.pixels;
            const double u = (2.0 * (x + 0.5) / w - 1.0 + ox) / sx;
            const double v = (1.0 - 2.0 * (y + 0.5) / h + oy) / sy;
            const double wt = 1.0 / zt, wd = 1.0 / zd;
            // The direction the shift is largest for: t = B (-p/|p|, |p|) / sqrt(1 + |p|^2).
            const double r = std::hypot(u, v);
            const glm::dvec3 worst = r > 0.0
                                         ? b * glm::dvec3(-u / r, -v / r, r) / std::sqrt(1 + r * r)
                                         : glm::dvec3(b, 0.0, 0.0);
            double largest = 0.0;
            auto shift = [&](const glm::dvec3& t) {
                const double dt = 1.0 - t.z * wt, dd = 1.0 - t.z * wd;
                if (dt <= 0.0 || dd <= 0.0) return;  // at or behind the moved camera
                const double ex = fx * (t.z * u - t.x), ey = fy * (t.z * v - t.y);
                largest = std::max(largest, std::hypot(ex, ey) * std::abs(wt - wd) / (dt * dd));
            };
            for (const glm::dvec3& t : cube) shift(t);
            shift(worst);
            shift(-worst);
            result.max_px = std::max(result.max_px, largest);
            if (largest > bound_px) ++result.pixels_over_bound;
        }
    return result;
}

}  // namespace reprise::codec
