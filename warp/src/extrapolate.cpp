#include <atomic>
#include <cmath>
#include <limits>
#include <utility>

#include "fruc_stages.hpp"
#include "kernels.hpp"
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

}  // namespace

StaticLayerTest::StaticLayerTest(const StaticReprojection& previous,
                                 const StaticReprojection& future, int image_width,
                                 int image_height, float tolerance)
    : projection(previous.unprojector().projection()),
      to_previous(previous.to_clip()),
      to_future(future.to_clip()),
      background_zv(previous.unprojector().perspective() ? -1.0f
                                                         : -previous.unprojector().far_plane()),
      background_w(previous.unprojector().perspective() ? 0.0f : 1.0f),
      width(float(image_width)),
      height(float(image_height)),
      tolerance2(tolerance * tolerance) {}

// classify_row for an axis-aligned projection, written without branches (it vectorises):
// Unprojector::point_ndc and StaticReprojection::land spelled out.
std::size_t static_layer_row_reference(const StaticLayerTest& t, int y, int x_begin, int x_end,
                                       const float* __restrict depth,
                                       const glm::vec2* __restrict motion,
                                       float* __restrict depth_out,
                                       glm::vec2* __restrict motion_out) {
    // Copies: the stores below could otherwise alias the matrices and the loop would not vectorise.
    const glm::mat4 P = t.projection, A = t.to_previous, B = t.to_future;
    const float background_zv = t.background_zv, background_w = t.background_w;
    const float fw = t.width, fh = t.height, tolerance2 = t.tolerance2;
    const float* __restrict m_row = &motion->x;
    float* __restrict m_out = &motion_out->x;
    const float py = float(y) + 0.5f, ny = 1.0f - 2.0f * py / fh;
    const float inf = std::numeric_limits<float>::infinity();
    unsigned dynamic = 0;
    for (int x = x_begin; x < x_end; ++x) {
        const float z = depth[x], mx = m_row[2 * x], my = m_row[2 * x + 1];
        const float px = float(x) + 0.5f, nx = 2.0f * px / fw - 1.0f;
        const bool background = z == inf;
        const float zv = background ? background_zv : -z;
        const float w = background ? background_w : 1.0f;
        const float wc = P[2][3] * zv + P[3][3] * w;
        const float vx = (nx * wc - P[2][0] * zv - P[3][0] * w) / P[0][0];
        const float vy = (ny * wc - P[2][1] * zv - P[3][1] * w) / P[1][1];
        auto clip = [&](const glm::mat4& M, int row) {
            return transform_row(M, row, vx, vy, zv, w);
        };
        const float aw = clip(A, 3), bw = clip(B, 3);
        const float bx = (clip(A, 0) / aw * 0.5f + 0.5f) * fw;
        const float by = (0.5f - 0.5f * clip(A, 1) / aw) * fh;
        const float lx = (clip(B, 0) / bw * 0.5f + 0.5f) * fw;
        const float ly = (0.5f - 0.5f * clip(B, 1) / bw) * fh;
        const float ex = bx - px - mx, ey = by - py - my;
        const bool still = (z == z) & (mx - mx == 0.0f) & (my - my == 0.0f) & (aw > 0.0f) &
                           (bw > 0.0f) & (ex * ex + ey * ey <= tolerance2);
        depth_out[x] = still ? z : kNaN;
        m_out[2 * x] = still ? lx - px : kNaN;
        m_out[2 * x + 1] = still ? ly - py : kNaN;
        dynamic += !still;
    }
    return dynamic;
}

namespace {

// Without a camera nothing tells static from moving: every pixel goes along its own motion.
void extrapolate_along_motion(const GBufferView& given, float s, float motion_scale,
                              const FrucOptions& options, FrucScratch& scratch, Frame& out,
                              FrucCounters& counters) {
    const GBufferView f = warp_input(given, 0, options, scratch, counters);
    const int w = f.width(), h = f.height();
    out.color.resize(w, h);
    out.depth.resize(w, h);
    out.motion.resize(w, h);
    scratch.valid.resize(w, h);
    const WarpTarget target{out.color.view(), out.depth.view(), out.motion.view(),
                            scratch.valid.view()};
    const std::size_t covered = warp_into(f, -s, options, scratch, target, counters);
    fill_holes(out.color.view(), scratch.valid.view(), out.depth.view(),
               std::size_t(w) * std::size_t(h) - covered, options, scratch, counters);
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            glm::vec2* m = out.motion.data() + std::size_t(y) * w;
            for (int x = 0; x < w; ++x) m[x] *= motion_scale;
        }
    });
}

}  // namespace

std::size_t static_layer(const GBufferView& f, const glm::mat4& to_view,
                         const glm::mat4& to_projection, float tolerance,
                         ImageView<float> depth_out, ImageView<glm::vec2> motion_out) {
    const int w = f.width(), h = f.height();
    // Where each pixel's surface was under the previous camera (camera-only motion) and where it
    // is under the target one, both from the same view-space point.
    const StaticReprojection to_previous = camera_only_motion(f.camera, w, h);
    const StaticReprojection to_target(f.camera, to_view, to_projection, w, h);
    const bool axis_aligned = to_previous.unprojector().axis_aligned();
    const StaticLayerTest axis_aligned_test(to_previous, to_target, w, h, tolerance);
    const float tolerance2 = tolerance * tolerance;
    std::atomic<std::size_t> dynamic{0};
    parallel_for(0, h, [&](int y0, int y1) {
        std::size_t local = 0;
        for (int y = y0; y < y1; ++y) {
            if (axis_aligned)
                local += static_layer_row(axis_aligned_test, y, w, f.depth.row(y), f.motion.row(y),
                                          depth_out.row(y), motion_out.row(y));
            else
                local += classify_row(f, y, to_previous, to_target, tolerance2, depth_out.row(y),
                                      motion_out.row(y));
        }
        dynamic += local;
    });
    return dynamic.load();
}

std::size_t extrapolation_displacement(const GBufferView& f, const glm::mat4& view,
                                       const glm::mat4& projection, float periods,
                                       float static_tolerance, ImageView<float> layer_depth,
                                       ImageView<glm::vec2> displacement) {
    const int w = f.width(), h = f.height();
    const std::size_t moving =
        static_layer(f, view, projection, static_tolerance, layer_depth, displacement);
    if (moving)
        parallel_for(0, h, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const float* still = layer_depth.row(y);
                const glm::vec2* own = f.motion.row(y);
                glm::vec2* d = displacement.row(y);
                for (int x = 0; x < w; ++x)
                    if (std::isnan(still[x])) d[x] = -periods * own[x];
            }
        });
    return moving;
}

Status extrapolate_frame(const GBufferView& f, float s, float motion_scale,
                         const FrucOptions& options, FrucScratch& scratch, Frame& out,
                         FrucCounters& counters) {
    if (!has_projection(f.camera))
        return extrapolate_to_camera(f, glm::mat4(1.0f), glm::mat4(1.0f), s, motion_scale, options,
                                     scratch, out, counters);
    const Camera& c = f.camera;
    Camera previous = c;
    previous.view = c.prev_view;
    previous.projection = c.prev_projection;
    previous.time = c.time - 1.0;
    const Camera future = camera_between(previous, c, 1.0f + s);
    return extrapolate_to_camera(f, future.view, future.projection, s, motion_scale, options,
                                 scratch, out, counters);
}

Status extrapolate_to_camera(const GBufferView& given, const glm::mat4& future_view,
                             const glm::mat4& future_projection, float s, float motion_scale,
                             const FrucOptions& options, FrucScratch& scratch, Frame& out,
                             FrucCounters& counters) {
    if (options.backend)
        return options.backend->extrapolate(backend_input(given, 0, options, scratch, counters),
                                            future_view, future_projection, s, motion_scale,
                                            options, out, counters, scratch.input_key[0]);
    if (!has_projection(given.camera)) {
        extrapolate_along_motion(given, s, motion_scale, options, scratch, out, counters);
        finish_colour(out.color.view(), options);
        return {};
    }
    const GBufferView f = warp_input(given, 0, options, scratch, counters);
    const int w = f.width(), h = f.height();
    // One warp of the whole frame: static pixels (whose motion the camera alone explains) to
    // where the future camera sees them, the others s periods on along their own motion. Warping
    // the moving objects as a layer of their own over the static one lost up to 4 dB: the static
    // layer's holes where they had been were filled from around before they were drawn back.
    scratch.layer_depth.resize(w, h);
    scratch.layer_motion.resize(w, h);
    const std::size_t moving_pixels =
        extrapolation_displacement(f, future_view, future_projection, s, options.static_tolerance,
                                   scratch.layer_depth.view(), scratch.layer_motion.view());
    ++(moving_pixels ? counters.dynamic_layers : counters.dynamic_skipped);
    const GBufferView along{.color = f.color,
                            .depth = f.depth,
                            .motion = std::as_const(scratch.layer_motion).view(),
                            .camera = f.camera};
    out.color.resize(w, h);
    out.depth.resize(w, h);
    out.motion.resize(w, h);
    scratch.valid.resize(w, h);
    // Drawn straight into the output: where nothing lands, colour 0, depth +inf, motion 0.
    const WarpTarget target{out.color.view(), out.depth.view(), out.motion.view(),
                            scratch.valid.view()};
    const std::size_t covered = warp_into(along, 1.0f, options, scratch, target, counters);
    fill_holes(out.color.view(), scratch.valid.view(), out.depth.view(),
               std::size_t(w) * std::size_t(h) - covered, options, scratch, counters);
    // The warp carried each pixel's displacement to the future; backward motion per period is
    // that displacement reversed and divided by s. s = 0 (the frame's own instant, another
    // camera): no time passed, no motion to report.
    const float to_backward = s > 1e-6f ? -motion_scale / s : 0.0f;
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            glm::vec2* m = &out.motion(0, y);
            for (int x = 0; x < w; ++x) m[x] *= to_backward;
        }
    });
    finish_colour(out.color.view(), options);
    return {};
}

}  // namespace reprise::warp
