// Per-pixel displacement from one camera to another through depth (exact for static geometry).
#include "reprise/warp/displacement.hpp"

#include <cmath>
#include <limits>

#include "kernels.hpp"
#include "reprise/core/camera_math.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::warp {

DisplacementTest::DisplacementTest(const StaticReprojection& to_target, int image_width,
                                   int image_height)
    : projection(to_target.unprojector().projection()),
      to_clip(to_target.to_clip()),
      to_view(to_target.to_view()),
      background_zv(to_target.unprojector().perspective() ? -1.0f
                                                          : -to_target.unprojector().far_plane()),
      background_w(to_target.unprojector().perspective() ? 0.0f : 1.0f),
      width(float(image_width)),
      height(float(image_height)) {}

// Branch-free so that it vectorises (Unprojector::point_ndc and StaticReprojection::land spelled
// out, same arithmetic).
void displacement_row_reference(const DisplacementTest& t, int y, int x_begin, int x_end,
                                const float* __restrict depth, glm::vec2* __restrict displacement,
                                float* __restrict target_depth) {
    // Copies: the stores below could otherwise alias them and the loop would not vectorise.
    const glm::mat4 P = t.projection, M = t.to_clip, V = t.to_view;
    const float background_zv = t.background_zv, background_w = t.background_w;
    const float fw = t.width, fh = t.height;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    float* __restrict d_out = &displacement->x;
    const float py = float(y) + 0.5f, ny = 1.0f - 2.0f * py / fh;
    for (int x = x_begin; x < x_end; ++x) {
        const float z = depth[x];
        const float px = float(x) + 0.5f, nx = 2.0f * px / fw - 1.0f;
        const bool background = z == inf;
        const float zv = background ? background_zv : -z;
        const float w = background ? background_w : 1.0f;
        const float wc = P[2][3] * zv + P[3][3] * w;
        const float vx = (nx * wc - P[2][0] * zv - P[3][0] * w) / P[0][0];
        const float vy = (ny * wc - P[2][1] * zv - P[3][1] * w) / P[1][1];
        const float cw = transform_row(M, 3, vx, vy, zv, w);
        const float lx = (transform_row(M, 0, vx, vy, zv, w) / cw * 0.5f + 0.5f) * fw;
        const float ly = (0.5f - 0.5f * transform_row(M, 1, vx, vy, zv, w) / cw) * fh;
        const float tz = -transform_row(V, 2, vx, vy, zv, w);
        const bool ok = (z >= 0.0f) & (cw > 0.0f) & (lx - lx == 0.0f) & (ly - ly == 0.0f);
        d_out[2 * x] = ok ? lx - px : nan;
        d_out[2 * x + 1] = ok ? ly - py : nan;
        target_depth[x] = ok ? (background ? inf : tz) : nan;
    }
}

void camera_displacement(const GBufferView& source, const Camera& target,
                         ImageView<glm::vec2> displacement, ImageView<float> target_depth) {
    const int w = source.depth.width, h = source.depth.height;
    REPRISE_ASSERT(displacement.width == w && displacement.height == h);
    REPRISE_ASSERT(target_depth.width == w && target_depth.height == h);
    // Orthographic background has no direction: it is the far plane (Unprojector).
    const StaticReprojection to_target(source.camera, target.view, target.projection, w, h);
    const Unprojector& unproject = to_target.unprojector();
    const DisplacementTest test(to_target, w, h);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();

    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float* z_row = source.depth.row(y);
            glm::vec2* d_row = displacement.row(y);
            float* t_row = target_depth.row(y);
            if (unproject.axis_aligned()) {
                displacement_row(test, y, w, z_row, d_row, t_row);
                continue;
            }
            const float py = float(y) + 0.5f, ny = unproject.ndc_y(py);
            for (int x = 0; x < w; ++x) {
                const float px = float(x) + 0.5f;
                const float z = z_row[x];
                glm::vec2 landing;
                const glm::vec4 point =
                    z >= 0.0f ? unproject.point_ndc(unproject.ndc_x(px), ny, z) : glm::vec4(nan);
                if (!(z >= 0.0f) || !to_target.land(point, landing) || !std::isfinite(landing.x) ||
                    !std::isfinite(landing.y)) {  // NaN or negative depth, behind the target
                    d_row[x] = {nan, nan};
                    t_row[x] = nan;
                    continue;
                }
                d_row[x] = {landing.x - px, landing.y - py};
                t_row[x] = z == inf ? inf : to_target.target_depth(point);
            }
        }
    });
}

}  // namespace reprise::warp
