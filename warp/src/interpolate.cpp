#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <utility>

#include "band.hpp"
#include "fruc_stages.hpp"
#include "kernels.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/warp/perceptual.hpp"
#include "reprise/warp/sample.hpp"
#include "reprise/warp/silhouettes.hpp"

namespace reprise::warp {

void WarpBuffers::resize(int w, int h) {
    if (color.width() == w && color.height() == h) return;
    color.resize(w, h);
    depth.resize(w, h);
    motion.resize(w, h);
    covered.resize(w, h);
}

// Reverse warp: the splat placed, at each covered pixel q, the source pixel p that lands there;
// refine p = q - factor * motion(p) with the source's own (bilinear) motion and fetch colour
// bicubically there. Taps are not depth-tested: across silhouettes the blend measured closer to
// the rendered truth than keeping either surface.
void refetch_row_reference(const RefetchRow& r, int x_begin, int x_end) {
    const int sw = r.color.width, sh = r.color.height;
    for (int x = x_begin; x < x_end; ++x) {
        if (!r.covered[x]) continue;
        const glm::vec2 q(float(x) + 0.5f, float(r.y) + 0.5f);
        glm::vec2 p = q - r.factor * r.target_motion[x];
        const Bilinear b = bilinear_taps(p.x, p.y, sw, sh);
        if (!b.inside) continue;
        const glm::vec2 m = bilinear_fetch(r.motion, b);
        if (!std::isfinite(m.x) || !std::isfinite(m.y)) continue;
        p = q - r.factor * m;
        if (!(p.x >= 0.0f && p.y >= 0.0f && p.x <= float(sw) && p.y <= float(sh))) continue;
        const glm::vec4 c = bicubic_fetch(r.color, p.x, p.y);
        if (std::isfinite(c.r + c.g + c.b + c.a)) r.out[x] = c;
    }
}

void bicubic_row_reference(const BicubicRow& r) {
    for (int i = 0; i < r.count; ++i)
        r.out[i] = bicubic_fetch(r.color, r.positions[i].x, r.positions[i].y);
}

namespace {

struct Refetch {
    const GBufferView& source;
    float factor;
};

// The refetch of a band of the splat's target while it is in cache.
void refetch_band(const Band& band, const void* context) {
    const Refetch& r = *static_cast<const Refetch*>(context);
    const WarpTarget& v = band.view;
    for (int row = 0; row < v.color.height; ++row)
        refetch_row({.color = r.source.color,
                     .motion = r.source.motion,
                     .factor = r.factor,
                     .y = band.y0 + row,
                     .width = v.color.width,
                     .covered = v.covered.row(row),
                     .target_motion = v.motion.row(row),
                     .out = v.color.row(row)});
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
            REPRISE_ASSERT(!out.motion.empty());
            REPRISE_ASSERT(source.motion.width == source.width() &&
                           source.motion.height == source.height());
            REPRISE_ASSERT(double(source.width()) * source.height() < double(1 << 30));
            const Refetch refetch{source, factor};
            return splat_refined(source, factor, out, {.footprint = 2}, refetch_band, &refetch);
        }
        case WarpMethod::Auto:  // resolved per frame by the converter
            REPRISE_ASSERT(options.warp != WarpMethod::Auto);
    }
    return 0;
}

uint64_t next_frame_key() {
    static std::atomic<uint64_t> last{0};
    return ++last;
}

GBufferView warp_input(const GBufferView& f, int slot, const FrucOptions& options,
                       FrucScratch& scratch, FrucCounters& counters, bool for_backend) {
    const bool widen = options.widen_silhouettes && !f.depth.empty() &&
                       !(for_backend && options.backend->widens_silhouettes());
    const bool encode = encodes_colour(options) && !f.color.empty();
    if (!widen && !encode) return f;
    auto prepared = [&](int i) {
        GBufferView v = f;
        if (widen) {
            v.depth = std::as_const(scratch.wide_depth[i]).view();
            if (!f.motion.empty()) v.motion = std::as_const(scratch.wide_motion[i]).view();
        }
        if (encode) v.color = std::as_const(scratch.encoded_color[i]).view();
        return v;
    };
    const uint64_t key = scratch.input_key[slot], other = scratch.input_key[1 - slot];
    const int as = int(widen) | int(encode) << 1;
    int buffer = slot;
    if (key != 0) {
        for (int i = 0; i < 2; ++i)
            if (scratch.prepared_key[i] == key && scratch.prepared_as[i] == as) return prepared(i);
        // The other input's copy as this call prepares it stays: its side of the frame uses it.
        if (other != 0 && scratch.prepared_key[buffer] == other &&
            scratch.prepared_as[buffer] == as)
            buffer = 1 - buffer;
    }
    if (widen) {
        std::size_t changed = 0;
        widen_silhouettes(f, scratch.wide_depth[buffer], scratch.wide_motion[buffer], &changed);
        counters.silhouette_pixels += changed;
        if (options.backend && key != 0) options.backend->silhouettes_counted(key);
    }
    if (encode) encode_perceptual(f.color, scratch.encoded_color[buffer]);
    scratch.prepared_key[buffer] = key;
    scratch.prepared_as[buffer] = as;
    return prepared(buffer);
}

GBufferView backend_input(const GBufferView& f, int slot, const FrucOptions& options,
                          FrucScratch& scratch, FrucCounters& counters) {
    return warp_input(f, slot, options, scratch, counters, true);
}

void fill_holes(ImageView<glm::vec4> color, ImageView<uint8_t> valid, ImageView<float> depth,
                std::size_t holes, const FrucOptions& options, FrucScratch& scratch,
                FrucCounters& counters) {
    if (holes && options.fill != FillMethod::None && options.border_run > 0) {
        const std::size_t border = continue_border_rows(color, depth, valid, options.border_run);
        counters.border_pixels += border;
        holes -= std::min(holes, border);
    }
    counters.hole_pixels += holes;
    if (holes == 0 || options.fill == FillMethod::None) {
        counters.fills_skipped += holes == 0;
        return;
    }
    ++counters.fills;
    if (options.fill == FillMethod::PullPush)
        scratch.pull_push.fill(color, valid, depth);
    else if (options.fill == FillMethod::Patch)
        scratch.patch.fill(color, valid, depth);
    else
        scratch.andreev.fill(color, valid, depth);
}

std::size_t blend_row_reference(const BlendRow& r) {
    const float inf = std::numeric_limits<float>::infinity();
    const float s = r.s;
    std::size_t holes = 0;
    for (int x = 0; x < r.width; ++x) {
        const bool ca = r.covered_a[x], cb = r.covered_b[x];
        const float za = r.depth_a[x], zb = r.depth[x];
        r.valid[x] = ca || cb;
        if (!ca) {  // b alone (or nothing: colour 0, depth +inf, motion 0 already)
            holes += !cb;
            r.motion[x] *= r.motion_scale;
            continue;
        }
        const bool stretched_a = r.covered_a[x] == kCoveredStretched,
                   stretched_b = r.covered_b[x] == kCoveredStretched;
        if (cb && stretched_a != stretched_b) {  // the side not stretched over a disocclusion
            if (stretched_b)
                r.color[x] = r.color_a[x], r.depth[x] = za, r.motion[x] = r.motion_a[x];
        } else if (cb && std::abs(za - zb) <= kSameSurface * std::min(za, zb)) {
            r.color[x] = (1.0f - s) * r.color_a[x] + s * r.color[x];
            r.depth[x] = std::min(za, zb);
        } else if (cb && std::isinf(za) && std::isinf(zb)) {
            r.color[x] = (1.0f - s) * r.color_a[x] + s * r.color[x];
            r.depth[x] = inf;
        } else if (!cb || !(zb < za)) {
            r.color[x] = r.color_a[x], r.depth[x] = za, r.motion[x] = r.motion_a[x];
        }
        r.motion[x] *= r.motion_scale;
    }
    return holes;
}

void interpolate_frame(const GBufferView& a_in, const GBufferView& b_in, float s, bool use_a,
                       float motion_scale, const FrucOptions& options, FrucScratch& scratch,
                       Frame& out, FrucCounters& counters) {
    const GBufferView a = use_a ? warp_input(a_in, 0, options, scratch, counters) : a_in,
                      b = warp_input(b_in, 1, options, scratch, counters);
    const int w = b.width(), h = b.height();
    out.color.resize(w, h);
    out.depth.resize(w, h);
    out.motion.resize(w, h);
    scratch.valid.resize(w, h);
    // b is warped straight into the output, a beside it; the blend then merges a in place.
    WarpBuffers& wa = scratch.side_a;
    wa.resize(w, h);
    scratch.side_b.covered.resize(w, h);
    const WarpTarget into_out{out.color.view(), out.depth.view(), out.motion.view(),
                              scratch.side_b.covered.view()};
    GBufferView from_a = a, from_b = b;
    const bool geometry = options.true_motion && !a.depth.empty() && !b.depth.empty() &&
                          !a.motion.empty() && !b.motion.empty();
    const bool cameras = geometry && has_projection(a.camera) && has_projection(b.camera);
    const Camera at = cameras ? camera_between(a.camera, b.camera, s) : Camera{};
    const bool linear = cameras && motion_is_linear(b, at, 1.0f - s, options.static_tolerance) &&
                        (!use_a || motion_is_linear(a, at, -s, options.static_tolerance));
    counters.linear_motion += linear;
    if (cameras && !linear) {
        ++counters.true_motion;
        scratch.true_b.resize(w, h);
        motion_toward(b, at, 1.0f - s, {}, options.static_tolerance, scratch.layer_depth,
                      scratch.true_b.view());
        from_b.motion = scratch.true_b.view();
        if (use_a) {
            invert_motion(b, options.static_tolerance, scratch.layer_depth, scratch.inverted,
                          scratch.inverted_depth);
            scratch.true_a.resize(w, h);
            motion_toward(a, at, -s, std::as_const(scratch.inverted).view(),
                          options.static_tolerance, scratch.layer_depth, scratch.true_a.view());
            from_a.motion = scratch.true_a.view();
        }
    } else if (geometry && use_a && !has_projection(b.camera)) {
        // No cameras (Blender's passes): anything may move, so a follows b's backward motion
        // inverted wherever some pixel of b lands, its own negated elsewhere.
        ++counters.true_motion;
        invert_motion(b, options.static_tolerance, scratch.layer_depth, scratch.inverted,
                      scratch.inverted_depth);
        scratch.true_a.resize(w, h);
        parallel_for(0, h, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const glm::vec2 *inverted = &scratch.inverted(0, y), *own = a.motion.row(y);
                glm::vec2* out_row = &scratch.true_a(0, y);
                for (int x = 0; x < w; ++x)
                    out_row[x] = std::isfinite(inverted[x].x) ? inverted[x] : own[x];
            }
        });
        from_a.motion = scratch.true_a.view();
    }
    warp_into(from_b, 1.0f - s, options, scratch, into_out, counters);
    if (use_a)
        warp_into(from_a, -s, options, scratch, wa.target(), counters);
    else
        wa.covered.fill(0);
    const bool refine =
        options.refine.enabled && use_a &&
        scratch.refiner.prepare(a, b, s,
                                {std::as_const(wa.color).view(), std::as_const(wa.depth).view(),
                                 std::as_const(wa.covered).view()},
                                {std::as_const(out.color).view(), std::as_const(out.depth).view(),
                                 std::as_const(scratch.side_b.covered).view()},
                                options.refine, encodes_colour(options), counters);
    std::atomic<std::size_t> holes{0};
    parallel_for(0, h, [&](int y0, int y1) {
        std::size_t local_holes = 0;
        for (int y = y0; y < y1; ++y)
            local_holes += blend_row({.covered_a = &wa.covered(0, y),
                                      .covered_b = &scratch.side_b.covered(0, y),
                                      .depth_a = &wa.depth(0, y),
                                      .color_a = &wa.color(0, y),
                                      .motion_a = &wa.motion(0, y),
                                      .depth = &out.depth(0, y),
                                      .color = &out.color(0, y),
                                      .motion = &out.motion(0, y),
                                      .valid = &scratch.valid(0, y),
                                      .width = w,
                                      .s = s,
                                      .motion_scale = motion_scale});
        holes += local_holes;
    });
    fill_holes(out.color.view(), scratch.valid.view(), out.depth.view(), holes.load(), options,
               scratch, counters);
    if (refine) scratch.refiner.apply(out.color.view());
    finish_colour(out.color.view(), options);
}

}  // namespace reprise::warp
