// Per-pixel displacement from one camera to another through depth (exact for static geometry).
#include <cmath>
#include <limits>

#include <glm/mat4x4.hpp>

#include "reprise/core/parallel.hpp"
#include "reprise/stereo/synthesize.hpp"

namespace reprise::stereo {

void stereo_displacement(const Frame& source, const Camera& target, ImageView<glm::vec2> displacement,
                         ImageView<float> target_depth) {
    const int w = source.width(), h = source.height();
    REPRISE_ASSERT(source.depth.width() == w && source.depth.height() == h);
    REPRISE_ASSERT(displacement.width == w && displacement.height == h);
    REPRISE_ASSERT(target_depth.width == w && target_depth.height == h);
    const glm::mat4& p = source.camera.projection;
    const bool perspective = p[2][3] != 0.0f;
    // Source camera space -> target camera space.
    const glm::mat4 to_target = target.view * glm::inverse(source.camera.view);
    const glm::mat4 target_clip = target.projection * to_target;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    // Orthographic background has no direction: it is the far plane.
    const float ortho_far = std::isfinite(source.camera.far) ? source.camera.far : 1e6f;

    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float* z_row = source.depth.data() + std::size_t(y) * w;
            glm::vec2* d_row = displacement.row(y);
            float* t_row = target_depth.row(y);
            const float py = float(y) + 0.5f;
            const float y_ndc = 1.0f - 2.0f * py / float(h);
            for (int x = 0; x < w; ++x) {
                const float px = float(x) + 0.5f;
                const float x_ndc = 2.0f * px / float(w) - 1.0f;
                float z = z_row[x];
                if (!(z >= 0.0f)) {  // NaN or negative
                    d_row[x] = {nan, nan};
                    t_row[x] = nan;
                    continue;
                }
                const bool background = z == inf;
                if (background && !perspective) z = ortho_far;
                glm::vec4 point;
                if (background && perspective) {
                    // The point at infinity through the pixel: direction with z_view = -1, w = 0.
                    // x_ndc = (P00 x + P20 z_v) / (P23 z_v) with P23 = -1.
                    const float wc = -p[2][3];
                    point = {(x_ndc * wc + p[2][0]) / p[0][0], (y_ndc * wc + p[2][1]) / p[1][1], -1.0f,
                             0.0f};
                } else {
                    const float zv = -z;
                    const float wc = p[2][3] * zv + p[3][3];
                    point = {(x_ndc * wc - p[2][0] * zv - p[3][0]) / p[0][0],
                             (y_ndc * wc - p[2][1] * zv - p[3][1]) / p[1][1], zv, 1.0f};
                }
                const glm::vec4 clip = target_clip * point;
                const float tz = -(to_target * point).z;
                if (!(clip.w > 0.0f) || !std::isfinite(clip.x) || !std::isfinite(clip.y)) {
                    d_row[x] = {nan, nan};
                    t_row[x] = nan;
                    continue;
                }
                const float tx = (clip.x / clip.w * 0.5f + 0.5f) * float(w);
                const float ty = (0.5f - 0.5f * clip.y / clip.w) * float(h);
                d_row[x] = {tx - px, ty - py};
                t_row[x] = background ? inf : tz;
            }
        }
    });
}

}  // namespace reprise::stereo
