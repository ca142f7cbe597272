#include <atomic>
#include <cmath>
#include <limits>

#include "fruc_stages.hpp"
#include "reprise/core/camera_math.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::warp {

void extrapolate_frame(const GBufferView& f, float s, float motion_scale, const FrucOptions& options,
                       FrucScratch& scratch, Frame& out, FrucCounters& counters) {
    const int w = f.width(), h = f.height();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const Camera& c = f.camera;
    Camera previous = c;
    previous.view = c.prev_view;
    previous.projection = c.prev_projection;
    previous.time = c.time - 1.0;
    const Camera future = camera_between(previous, c, 1.0f + s);
    // Where each pixel's surface was under the previous camera (camera-only motion) and where it
    // will be under the future one, both from the same view-space point.
    const StaticReprojection to_previous = camera_only_motion(c, w, h);
    const StaticReprojection to_future(c, future.view, future.projection, w, h);
    const Unprojector& unproject = to_previous.unprojector();

    // Static layer: pixels whose motion the camera alone explains, moved to the future camera;
    // the others are left out (depth and motion NaN).
    scratch.layer_depth.resize(w, h);
    scratch.layer_motion.resize(w, h);
    const ImageView<float> layer_depth = scratch.layer_depth.view();
    const ImageView<glm::vec2> layer_motion = scratch.layer_motion.view();
    std::atomic<std::size_t> dynamic{0};
    parallel_for(0, h, [&](int y0, int y1) {
        std::size_t local = 0;
        for (int y = y0; y < y1; ++y) {
            const float* z_row = f.depth.row(y);
            const glm::vec2* m_row = f.motion.row(y);
            float* d_out = layer_depth.row(y);
            glm::vec2* m_out = layer_motion.row(y);
            const float py = float(y) + 0.5f, ny = unproject.ndc_y(py);
            for (int x = 0; x < w; ++x) {
                const float z = z_row[x];
                const glm::vec2 m = m_row[x];
                const glm::vec2 p(float(x) + 0.5f, py);
                glm::vec2 before, later;
                bool still = !std::isnan(z) && std::isfinite(m.x) && std::isfinite(m.y);
                if (still) {
                    const glm::vec4 point = unproject.point_ndc(unproject.ndc_x(p.x), ny, z);
                    still = to_previous.land(point, before) && to_future.land(point, later) &&
                            glm::length(before - p - m) <= options.static_tolerance;
                }
                if (still) {
                    d_out[x] = z;
                    m_out[x] = later - p;
                } else {
                    d_out[x] = nan;
                    m_out[x] = glm::vec2(nan);
                    ++local;
                }
            }
        }
        dynamic += local;
    });
    const GBufferView layer{.color = f.color,
                            .depth = scratch.layer_depth.view(),
                            .motion = scratch.layer_motion.view(),
                            .camera = c};
    out.color.resize(w, h);
    out.depth.resize(w, h);
    out.motion.resize(w, h);
    scratch.valid.resize(w, h);
    // Drawn straight into the output: where nothing lands, colour 0, depth +inf, motion 0.
    const WarpTarget base{out.color.view(), out.depth.view(), out.motion.view(), scratch.valid.view()};
    const std::size_t covered = warp_into(layer, 1.0f, options, scratch, base, counters);
    fill_holes(out.color.view(), scratch.valid.view(), out.depth.view(),
               std::size_t(w) * std::size_t(h) - covered, options, scratch, counters);

    // The static layer carried its displacement to the future; backward motion per period is
    // that displacement reversed and divided by s (0 where nothing landed).
    const float to_backward = -motion_scale / s;
    const std::size_t moving_pixels = dynamic.load();
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            glm::vec2* m = out.motion.data() + std::size_t(y) * w;
            for (int x = 0; x < w; ++x) m[x] *= to_backward;
            if (moving_pixels == 0) continue;
            // The dynamic layer's depth: the input's where the static layer left a pixel out.
            const float* z_in = f.depth.row(y);
            const glm::vec2* m_static = layer_motion.row(y);
            float* z_layer = layer_depth.row(y);
            for (int x = 0; x < w; ++x) z_layer[x] = std::isnan(m_static[x].x) ? z_in[x] : nan;
        }
    });
    if (moving_pixels == 0) {
        ++counters.dynamic_skipped;
        return;
    }
    // Dynamic layer: the moving objects at their constant-velocity positions, over the static one.
    ++counters.dynamic_layers;
    const GBufferView moving_layer{
        .color = f.color, .depth = scratch.layer_depth.view(), .motion = f.motion, .camera = c};
    WarpBuffers& moving = scratch.side_a;
    moving.resize(w, h);
    splat(moving_layer, -s, moving.target(), options.splat);
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < w; ++x)
                if (moving.covered(x, y) && moving.depth(x, y) < out.depth(x, y)) {
                    out.color(x, y) = moving.color(x, y);
                    out.depth(x, y) = moving.depth(x, y);
                    out.motion(x, y) = moving.motion(x, y) * motion_scale;
                }
    });
}

}  // namespace reprise::warp
