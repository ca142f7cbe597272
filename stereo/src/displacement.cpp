// Per-pixel displacement from one camera to another through depth (exact for static geometry).
#include <cmath>
#include <limits>

#include "reprise/core/camera_math.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/stereo/synthesize.hpp"

namespace reprise::stereo {

void stereo_displacement(const GBufferView& source, const Camera& target,
                         ImageView<glm::vec2> displacement, ImageView<float> target_depth) {
    const int w = source.depth.width, h = source.depth.height;
    REPRISE_ASSERT(displacement.width == w && displacement.height == h);
    REPRISE_ASSERT(target_depth.width == w && target_depth.height == h);
    // Orthographic background has no direction: it is the far plane (Unprojector).
    const StaticReprojection to_target(source.camera, target.view, target.projection, w, h);
    const Unprojector& unproject = to_target.unprojector();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();

    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float* z_row = source.depth.row(y);
            glm::vec2* d_row = displacement.row(y);
            float* t_row = target_depth.row(y);
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

}  // namespace reprise::stereo
