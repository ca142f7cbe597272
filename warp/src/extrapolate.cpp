#include <atomic>
#include <cmath>
#include <limits>

#include "fruc_stages.hpp"
#include "reprise/core/camera_math.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::warp {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// The static-layer test of row y: a pixel is static when the camera alone explains its motion
// (its surface point lands within the tolerance of where its motion says it was); static pixels
// keep their depth and get their displacement to the future camera, the others NaN. Returns the
// number of others.
std::size_t classify_row(const GBufferView& f, int y, const StaticReprojection& to_previous,
                         const StaticReprojection& to_future, float tolerance2, float* depth_out,
                         glm::vec2* motion_out) {
    const Unprojector& unproject = to_previous.unprojector();
    const float* z_row = f.depth.row(y);
    const glm::vec2* m_row = f.motion.row(y);
    const float py = float(y) + 0.5f, ny = unproject.ndc_y(py);
    std::size_t dynamic = 0;
    for (int x = 0; x < f.depth.width; ++x) {
        const float z = z_row[x];
        const glm::vec2 m = m_row[x];
        const glm::vec2 p(float(x) + 0.5f, py);
        glm::vec2 before, later;
        bool still = !std::isnan(z) && std::isfinite(m.x) && std::isfinite(m.y);
        if (still) {
            const glm::vec4 point = unproject.point_ndc(unproject.ndc_x(p.x), ny, z);
            still = to_previous.land(point, before) && to_future.land(point, later);
            if (still) {
                const glm::vec2 error = before - p - m;
                still = glm::dot(error, error) <= tolerance2;
            }
        }
        depth_out[x] = still ? z : kNaN;
        motion_out[x] = still ? later - p : glm::vec2(kNaN);
        dynamic += !still;
    }
    return dynamic;
}

// The same for an axis-aligned projection, written without branches so that it vectorises:
// Unprojector::point_ndc and StaticReprojection::land spelled out.
std::size_t classify_row_axis_aligned(const GBufferView& f, int y,
                                      const StaticReprojection& to_previous,
                                      const StaticReprojection& to_future, float tolerance2,
                                      float* depth_out, glm::vec2* motion_out) {
    const Unprojector& unproject = to_previous.unprojector();
    // Copies: the stores below could otherwise alias the matrices and the loop would not vectorise.
    const glm::mat4 P = unproject.projection();
    const glm::mat4 A = to_previous.to_clip(), B = to_future.to_clip();
    const bool perspective = unproject.perspective();
    const float background_zv = perspective ? -1.0f : -unproject.far_plane();
    const float background_w = perspective ? 0.0f : 1.0f;
    const float fw = float(f.depth.width), fh = float(f.depth.height);
    const float* __restrict z_row = f.depth.row(y);
    const float* __restrict m_row = &f.motion.row(y)->x;
    float* __restrict m_out = &motion_out->x;
    float* __restrict d_out = depth_out;
    const float py = float(y) + 0.5f, ny = unproject.ndc_y(py);
    const float inf = std::numeric_limits<float>::infinity();
    const int width = f.depth.width;
    unsigned dynamic = 0;
    for (int x = 0; x < width; ++x) {
        const float z = z_row[x], mx = m_row[2 * x], my = m_row[2 * x + 1];
        const float px = float(x) + 0.5f, nx = unproject.ndc_x(px);
        const bool background = z == inf;
        const float zv = background ? background_zv : -z;
        const float w = background ? background_w : 1.0f;
        const float wc = P[2][3] * zv + P[3][3] * w;
        const float vx = (nx * wc - P[2][0] * zv - P[3][0] * w) / P[0][0];
        const float vy = (ny * wc - P[2][1] * zv - P[3][1] * w) / P[1][1];
        auto clip = [&](const glm::mat4& M, int row) { return transform_row(M, row, vx, vy, zv, w); };
        const float aw = clip(A, 3), bw = clip(B, 3);
        const float bx = (clip(A, 0) / aw * 0.5f + 0.5f) * fw;
        const float by = (0.5f - 0.5f * clip(A, 1) / aw) * fh;
        const float lx = (clip(B, 0) / bw * 0.5f + 0.5f) * fw;
        const float ly = (0.5f - 0.5f * clip(B, 1) / bw) * fh;
        const float ex = bx - px - mx, ey = by - py - my;
        const bool still = (z == z) & (mx - mx == 0.0f) & (my - my == 0.0f) & (aw > 0.0f) &
                           (bw > 0.0f) & (ex * ex + ey * ey <= tolerance2);
        d_out[x] = still ? z : kNaN;
        m_out[2 * x] = still ? lx - px : kNaN;
        m_out[2 * x + 1] = still ? ly - py : kNaN;
        dynamic += !still;
    }
    return dynamic;
}

}  // namespace

void extrapolate_frame(const GBufferView& f, float s, float motion_scale, const FrucOptions& options,
                       FrucScratch& scratch, Frame& out, FrucCounters& counters) {
    const Camera& c = f.camera;
    Camera previous = c;
    previous.view = c.prev_view;
    previous.projection = c.prev_projection;
    previous.time = c.time - 1.0;
    const Camera future = camera_between(previous, c, 1.0f + s);
    extrapolate_to_camera(f, future.view, future.projection, s, motion_scale, options, scratch, out, counters);
}

void extrapolate_to_camera(const GBufferView& f, const glm::mat4& future_view, const glm::mat4& future_projection,
                           float s, float motion_scale, const FrucOptions& options, FrucScratch& scratch,
                           Frame& out, FrucCounters& counters) {
    const int w = f.width(), h = f.height();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const Camera& c = f.camera;
    // Where each pixel's surface was under the previous camera (camera-only motion) and where it
    // will be under the future one, both from the same view-space point.
    const StaticReprojection to_previous = camera_only_motion(c, w, h);
    const StaticReprojection to_future(c, future_view, future_projection, w, h);
    const Unprojector& unproject = to_previous.unprojector();

    // Static layer: pixels whose motion the camera alone explains, moved to the future camera;
    // the others are left out (depth and motion NaN).
    scratch.layer_depth.resize(w, h);
    scratch.layer_motion.resize(w, h);
    const ImageView<float> layer_depth = scratch.layer_depth.view();
    const ImageView<glm::vec2> layer_motion = scratch.layer_motion.view();
    std::atomic<std::size_t> dynamic{0};
    const float tolerance2 = options.static_tolerance * options.static_tolerance;
    parallel_for(0, h, [&](int y0, int y1) {
        std::size_t local = 0;
        for (int y = y0; y < y1; ++y) {
            if (unproject.axis_aligned())
                local += classify_row_axis_aligned(f, y, to_previous, to_future, tolerance2,
                                                   layer_depth.row(y), layer_motion.row(y));
            else
                local += classify_row(f, y, to_previous, to_future, tolerance2, layer_depth.row(y),
                                      layer_motion.row(y));
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
    // s = 0 (the frame's own instant, another camera): no time passed, no motion to report.
    const float to_backward = s > 1e-6f ? -motion_scale / s : 0.0f;
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
