#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "fruc_stages.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/warp/sample.hpp"

namespace reprise::warp {

void WarpBuffers::resize(int w, int h) {
    if (color.width() == w && color.height() == h) return;
    color.resize(w, h);
    depth.resize(w, h);
    motion.resize(w, h);
    covered.resize(w, h);
}

bool motion_is_zero(const GBufferView& f) {
    if (f.motion.empty()) return false;
    for (int y = 0; y < f.motion.height; ++y) {
        const glm::vec2* m = f.motion.row(y);
        for (int x = 0; x < f.motion.width; ++x)
            if (m[x].x != 0.0f || m[x].y != 0.0f) return false;
    }
    return true;
}

namespace {

// Reverse warp: the splat placed, at each covered pixel q, the source pixel p that lands there;
// refine p = q - factor * motion(p) with the source's own (bilinear) motion and fetch colour
// bilinearly there. Taps are not depth-tested: across silhouettes the blend measured closer to the
// rendered truth than keeping either surface.
void refetch(const GBufferView& source, float factor, const WarpTarget& out) {
    const int w = out.color.width, h = out.color.height;
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < w; ++x) {
                if (!out.covered(x, y)) continue;
                glm::vec2 q(x + 0.5f, y + 0.5f);
                glm::vec2 p = q - factor * out.motion(x, y);
                Bilinear b = bilinear_taps(p.x, p.y, source.width(), source.height());
                if (!b.inside) continue;
                glm::vec2 m = bilinear_fetch(source.motion, b);
                if (!std::isfinite(m.x) || !std::isfinite(m.y)) continue;
                p = q - factor * m;
                b = bilinear_taps(p.x, p.y, source.width(), source.height());
                if (!b.inside) continue;
                glm::vec4 c = bicubic_fetch(source.color, p.x, p.y);
                if (std::isfinite(c.r + c.g + c.b + c.a)) out.color(x, y) = c;
            }
    });
}

}  // namespace

std::size_t warp_into(const GBufferView& source, float factor, const FrucOptions& options,
                      FrucScratch& scratch, const WarpTarget& out, FrucCounters& counters) {
    switch (options.warp) {
        case WarpMethod::Grid: {
            const GridStats stats = scratch.grid.warp(source, factor, out, options.grid);
            counters.grid_cells += stats.cells;
            return stats.covered;
        }
        case WarpMethod::Splat:
            return splat(source, factor, out, options.splat);
        case WarpMethod::Reverse: {
            const std::size_t covered = splat(source, factor, out, {.footprint = 2});
            refetch(source, factor, out);
            return covered;
        }
    }
    return 0;
}

void warp_frame(const GBufferView& source, float factor, const FrucOptions& options,
                FrucScratch& scratch, WarpBuffers& out, FrucCounters& counters) {
    out.resize(source.width(), source.height());
    warp_into(source, factor, options, scratch, out.target(), counters);
}

void fill_holes(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                ImageView<const float> depth, std::size_t holes, const FrucOptions& options,
                FrucScratch& scratch, FrucCounters& counters) {
    counters.hole_pixels += holes;
    if (holes == 0 || options.fill == FillMethod::None) {
        counters.fills_skipped += holes == 0;
        return;
    }
    ++counters.fills;
    if (options.fill == FillMethod::PullPush) scratch.pull_push.fill(color, valid, depth);
    else scratch.andreev.fill(color, valid, depth);
}

void interpolate_frame(const GBufferView& a, const GBufferView& b, float s, bool use_a,
                       float motion_scale, const FrucOptions& options, FrucScratch& scratch,
                       Frame& out, FrucCounters& counters) {
    const int w = b.width(), h = b.height();
    warp_frame(b, 1.0f - s, options, scratch, scratch.side_b, counters);
    if (use_a) {
        warp_frame(a, -s, options, scratch, scratch.side_a, counters);
    } else {
        scratch.side_a.resize(w, h);
        scratch.side_a.covered.fill(0);
    }
    out.color.resize(w, h);
    out.depth.resize(w, h);
    out.motion.resize(w, h);
    scratch.valid.resize(w, h);
    const WarpBuffers &wa = scratch.side_a, &wb = scratch.side_b;
    const float inf = std::numeric_limits<float>::infinity();
    std::atomic<std::size_t> holes{0};
    parallel_for(0, h, [&](int y0, int y1) {
        std::size_t local_holes = 0;
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < w; ++x) {
                bool ca = wa.covered(x, y), cb = wb.covered(x, y);
                float za = wa.depth(x, y), zb = wb.depth(x, y);
                glm::vec4 color(0.0f);
                float z = inf;
                glm::vec2 m(0.0f);
                if (ca && cb && std::abs(za - zb) <= 0.02f * std::min(za, zb)) {
                    color = (1.0f - s) * wa.color(x, y) + s * wb.color(x, y);
                    z = std::min(za, zb);
                    m = wb.motion(x, y);
                } else if (ca && cb && std::isinf(za) && std::isinf(zb)) {
                    color = (1.0f - s) * wa.color(x, y) + s * wb.color(x, y);
                    m = wb.motion(x, y);
                } else if (cb && (!ca || zb < za)) {
                    color = wb.color(x, y), z = zb, m = wb.motion(x, y);
                } else if (ca) {
                    color = wa.color(x, y), z = za, m = wa.motion(x, y);
                }
                out.color(x, y) = color;
                out.depth(x, y) = z;
                out.motion(x, y) = m * motion_scale;
                scratch.valid(x, y) = ca || cb;
                local_holes += !(ca || cb);
            }
        holes += local_holes;
    });
    fill_holes(out.color.view(), scratch.valid.view(), out.depth.view(), holes.load(), options,
               scratch, counters);
}

}  // namespace reprise::warp
