#include <cmath>
#include <limits>
#include <mutex>

#include "fruc_stages.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::warp {

namespace {

// Pixel position of a world point (w = 1) or direction (w = 0) under a view-projection.
bool to_pixels(const glm::mat4& view_projection, glm::vec4 world, int w, int h, glm::vec2& pixel) {
    glm::vec4 clip = view_projection * world;
    if (!(clip.w > 0.0f)) return false;
    pixel = {(clip.x / clip.w * 0.5f + 0.5f) * float(w), (0.5f - 0.5f * clip.y / clip.w) * float(h)};
    return true;
}

}  // namespace

void extrapolate_frame(const Frame& f, float s, const FrucOptions& options, FrucScratch& scratch,
                       Frame& out, FrucCounters& counters) {
    const int w = f.width(), h = f.height();
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const Camera& c = f.camera;
    Camera previous = c;
    previous.view = c.prev_view;
    previous.projection = c.prev_projection;
    previous.time = c.time - 1.0;
    const Camera future = camera_between(previous, c, 1.0f + s);
    const glm::mat4 unproject = glm::inverse(c.projection * c.view);
    const glm::mat4 to_previous = c.prev_projection * c.prev_view;
    const glm::mat4 to_future = future.projection * future.view;
    // A perspective projection without skew maps view depth d and NDC (nx, ny) to the view-space
    // point (d (nx + P20) / P00, d (ny + P21) / P11, -d): two matrix products per pixel instead of six.
    const glm::mat4& P = c.projection;
    const bool simple_perspective = P[3][3] == 0.0f && P[2][3] == -1.0f && P[1][0] == 0.0f &&
                                    P[0][1] == 0.0f && P[3][0] == 0.0f && P[3][1] == 0.0f &&
                                    P[0][0] != 0.0f && P[1][1] != 0.0f;
    const glm::mat4 camera_to_world = glm::inverse(c.view);
    const glm::mat4 view_to_previous = to_previous * camera_to_world;
    const glm::mat4 view_to_future = to_future * camera_to_world;

    // Static layer: pixels whose motion the camera alone explains, moved to the future camera.
    Frame& layer = scratch.layer;
    layer.color = f.color;
    layer.depth = f.depth;
    layer.motion.resize(w, h);
    std::size_t dynamic = 0;
    parallel_for(0, h, [&](int y0, int y1) {
        std::size_t local = 0;
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < w; ++x) {
                float z = f.depth(x, y);
                glm::vec2 m = f.motion(x, y);
                glm::vec2 p(x + 0.5f, y + 0.5f);
                glm::vec4 ndc(2.0f * p.x / w - 1.0f, 1.0f - 2.0f * p.y / h, 0.0f, 1.0f);
                glm::vec4 world;
                glm::mat4 const* previous_of = &to_previous;
                glm::mat4 const* future_of = &to_future;
                if (simple_perspective) {  // `world` holds the view-space point or direction
                    float d = std::isinf(z) ? 1.0f : z;
                    world = glm::vec4(d * (ndc.x + P[2][0]) / P[0][0], d * (ndc.y + P[2][1]) / P[1][1],
                                      -d, std::isinf(z) ? 0.0f : 1.0f);
                    previous_of = &view_to_previous;
                    future_of = &view_to_future;
                } else if (std::isinf(z)) {  // background: the direction through the pixel
                    glm::vec4 a = unproject * glm::vec4(glm::vec2(ndc), -1.0f, 1.0f);
                    glm::vec4 b = unproject * glm::vec4(glm::vec2(ndc), 0.0f, 1.0f);
                    world = glm::vec4(glm::vec3(b) / b.w - glm::vec3(a) / a.w, 0.0f);
                } else {
                    // The point at view depth z along the pixel's ray.
                    glm::vec4 a = unproject * glm::vec4(glm::vec2(ndc), -1.0f, 1.0f);
                    glm::vec4 b = unproject * glm::vec4(glm::vec2(ndc), 0.0f, 1.0f);
                    glm::vec3 pa = glm::vec3(a) / a.w, pb = glm::vec3(b) / b.w;
                    float za = -(c.view * glm::vec4(pa, 1.0f)).z, zb = -(c.view * glm::vec4(pb, 1.0f)).z;
                    float t = (z - za) / (zb - za);
                    world = glm::vec4(pa + t * (pb - pa), 1.0f);
                }
                glm::vec2 before, later;
                bool ok = std::isfinite(z) || std::isinf(z);
                ok = ok && std::isfinite(m.x) && std::isfinite(m.y);
                ok = ok && to_pixels(*previous_of, world, w, h, before) &&
                     to_pixels(*future_of, world, w, h, later);
                bool still = ok && glm::length(before - p - m) <= options.static_tolerance;
                if (still) {
                    layer.motion(x, y) = later - p;
                } else {
                    layer.depth(x, y) = nan;  // left out of the static layer
                    layer.motion(x, y) = glm::vec2(nan);
                    ++local;
                }
            }
        static std::mutex mutex;
        std::lock_guard lock(mutex);
        dynamic += local;
    });
    warp_frame(layer, 1.0f, options, scratch, scratch.side_b, counters);
    WarpBuffers& base = scratch.side_b;
    fill_holes(base.color.view(), base.covered.view(), base.depth.view(), options, scratch, counters);

    out.color = base.color;
    out.depth = base.depth;
    out.motion.resize(w, h);
    // The static layer carried its displacement to the future; backward motion per period is
    // that displacement reversed and divided by s. Filled holes get none.
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < w; ++x) {
                bool covered = base.covered(x, y);
                out.motion(x, y) = covered ? -base.motion(x, y) / s : glm::vec2(0.0f);
                if (!covered) out.depth(x, y) = std::numeric_limits<float>::infinity();
            }
    });
    if (dynamic == 0) {
        ++counters.dynamic_skipped;
        return;
    }
    // Dynamic layer: the moving objects at their constant-velocity positions, over the static one.
    ++counters.dynamic_layers;
    layer.depth = f.depth;
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < w; ++x)
                if (std::isfinite(scratch.layer.motion(x, y).x)) layer.depth(x, y) = nan;
    });
    layer.motion = f.motion;
    WarpBuffers& moving = scratch.side_a;
    moving.resize(w, h);
    splat(layer, -s, moving.target(), options.splat);
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < w; ++x)
                if (moving.covered(x, y) && moving.depth(x, y) < out.depth(x, y)) {
                    out.color(x, y) = moving.color(x, y);
                    out.depth(x, y) = moving.depth(x, y);
                    out.motion(x, y) = moving.motion(x, y);
                }
    });
}

}  // namespace reprise::warp
