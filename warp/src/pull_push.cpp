// Pull-push hole filling (Marroquim et al. 2007) with a depth-aware pull.
//
// Level 0 is the image; level s+1 has ceil(w/2) x ceil(h/2) pixels, each built from its (up to)
// four children. Levels store premultiplied rgb and the weight min(1, sum of child weights) in a.
// The push walks back down: a pixel with weight a < 1 becomes p + (1 - a) * up, where up is the
// bilinear upsampling of the (already filled) coarser level. At level 0 only holes are written.
#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>

#include "kernels.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/warp/fill.hpp"

namespace reprise::warp {

namespace {

using glm::vec3;
using glm::vec4;

bool finite_rgb(const vec4& c) {
    return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b);
}

float sane_depth(float d) { return std::isnan(d) ? INFINITY : std::max(d, 0.0f); }

struct Child {
    vec3 p;  // premultiplied rgb
    float w;
    float d;
};

// One coarser pixel from up to four children given in the order (0,0) (1,0) (0,1) (1,1). With
// depth, children nearer than the farthest one by more than the ratio are left out.
void pull_pixel(const Child* child, int n, bool use_depth, vec4& out, float& out_depth) {
    float dmax = 0.0f;
    if (use_depth) {
        bool any = false;
        for (int k = 0; k < n; ++k)
            if (child[k].w > 0.0f) {
                dmax = any ? std::max(dmax, child[k].d) : child[k].d;
                any = true;
            }
    }
    vec3 p(0.0f);
    float w = 0.0f;
    for (int k = 0; k < n; ++k)
        if (child[k].w > 0.0f && (!use_depth || child[k].d * kBackgroundDepthRatio >= dmax)) {
            p += child[k].p;
            w += child[k].w;
        }
    out = w > 1.0f ? vec4(p / w, 1.0f) : vec4(p, w);
    out_depth = dmax;
}

// Bilinear taps of fine coordinate x on a level of n pixels: the fine centre x + 0.5 sits at
// x / 2 - 0.25 in coarse pixel units, so the weights are 1/4 and 3/4.
struct Taps {
    int i0, i1;
    float w0, w1;
};
Taps taps(int x, int n) {
    int i = x >> 1;
    if (x & 1) return {i, std::min(i + 1, n - 1), 0.75f, 0.25f};
    return {std::max(i - 1, 0), i, 0.25f, 0.75f};
}

// The filled coarse level `c` (all weights 1) upsampled at fine pixel (x, y). With depth `d`,
// taps nearer than the farthest by more than the ratio are dropped; `out_depth` = farthest.
vec3 upsample(const Image<vec4>& c, const Image<float>* d, int x, int y, float& out_depth) {
    const Taps tx = taps(x, c.width()), ty = taps(y, c.height());
    const int xs[4] = {tx.i0, tx.i1, tx.i0, tx.i1};
    const int ys[4] = {ty.i0, ty.i0, ty.i1, ty.i1};
    float w[4] = {tx.w0 * ty.w0, tx.w1 * ty.w0, tx.w0 * ty.w1, tx.w1 * ty.w1};
    out_depth = 0.0f;
    if (d) {
        float dk[4];
        for (int k = 0; k < 4; ++k) dk[k] = (*d)(xs[k], ys[k]);
        out_depth = std::max(std::max(dk[0], dk[1]), std::max(dk[2], dk[3]));
        for (int k = 0; k < 4; ++k)
            if (!(dk[k] * kBackgroundDepthRatio >= out_depth)) w[k] = 0.0f;
    }
    if (w[0] > 0.0f && w[1] > 0.0f && w[2] > 0.0f && w[3] > 0.0f)  // weights sum to exactly 1
        return vec3(vec4(0.0f) + c(xs[0], ys[0]) * w[0] + c(xs[1], ys[1]) * w[1] +
                    c(xs[2], ys[2]) * w[2] + c(xs[3], ys[3]) * w[3]);
    vec3 acc(0.0f);
    float wsum = 0.0f;
    for (int k = 0; k < 4; ++k)
        if (w[k] > 0.0f) {
            acc += vec3(c(xs[k], ys[k])) * w[k];
            wsum += w[k];
        }
    return acc / wsum;
}

// Fills the pixels of level `s` (colour + optional depth) whose weight is below 1 from the
// filled level above it; rows [y0, y1).
void push_rows(Image<vec4>& fine, Image<float>* fine_d, const Image<vec4>& coarse,
               const Image<float>* coarse_d, int y0, int y1) {
    for (int y = y0; y < y1; ++y)
        for (int x = 0; x < fine.width(); ++x) {
            vec4& px = fine(x, y);
            if (px.a >= 1.0f) continue;
            float ud;
            const vec3 up = upsample(coarse, coarse_d, x, y, ud);
            if (fine_d && px.a == 0.0f) (*fine_d)(x, y) = ud;
            px = vec4(vec3(px) + (1.0f - px.a) * up, 1.0f);
        }
}

// Normalises a top level that still has partial weights; false when it has an empty pixel
// (only possible when the image has no valid pixel at all).
bool finish_top(Image<vec4>& top) {
    for (std::size_t i = 0; i < top.pixel_count(); ++i) {
        vec4& px = top.data()[i];
        if (px.a == 0.0f) return false;
        if (px.a < 1.0f) px = vec4(vec3(px) / px.a, 1.0f);
    }
    return true;
}

int grain_rows(int width) { return std::max(1, 16384 / std::max(width, 1)); }

void check_inputs(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                  ImageView<const float> depth) {
    REPRISE_ASSERT(valid.width == color.width && valid.height == color.height);
    REPRISE_ASSERT(depth.empty() || (depth.width == color.width && depth.height == color.height));
}

}  // namespace

std::size_t pull_level_row_reference(const PullLevelRow& r, int i_begin, int i_end) {
    const bool use_depth = r.depth0 != nullptr;
    std::size_t empty = 0;
    for (int i = i_begin; i < i_end; ++i) {
        const int x0 = 2 * i;
        if (x0 + 1 < r.fine_width && r.rows == 2) {
            const vec4 &a = r.row0[x0], &b = r.row0[x0 + 1], &e = r.row1[x0], &g = r.row1[x0 + 1];
            if (a.a == 1.0f && b.a == 1.0f && e.a == 1.0f && g.a == 1.0f) {
                float dmax = 0.0f;
                bool same_layer = true;
                if (use_depth) {
                    const float d[4] = {r.depth0[x0], r.depth0[x0 + 1], r.depth1[x0],
                                        r.depth1[x0 + 1]};
                    dmax = std::max(std::max(d[0], d[1]), std::max(d[2], d[3]));
                    for (float dk : d) same_layer &= dk * kBackgroundDepthRatio >= dmax;
                }
                if (same_layer) {  // pull_pixel's arithmetic, in its order
                    r.out[i] = vec4(vec3(vec4(0.0f) + a + b + e + g) / 4.0f, 1.0f);
                    if (use_depth) r.out_depth[i] = dmax;
                    continue;
                }
            }
        }
        Child child[4];
        int n = 0;
        for (int dy = 0; dy < r.rows; ++dy)
            for (int dx = 0; dx < 2 && x0 + dx < r.fine_width; ++dx) {
                const vec4& p = (dy ? r.row1 : r.row0)[x0 + dx];
                child[n++] = {vec3(p), p.a, use_depth ? (dy ? r.depth1 : r.depth0)[x0 + dx] : 0.0f};
            }
        float d;
        pull_pixel(child, n, use_depth, r.out[i], d);
        if (use_depth) r.out_depth[i] = d;
        empty += r.out[i].a < 1.0f;
    }
    return empty;
}

PullCounts pull_row_reference(const PullRow& r, int i_begin, int i_end) {
    const bool use_depth = r.depth0 != nullptr;
    const int width = r.fine_width, ny = r.rows;
    const vec4* row0 = r.row0;
    const vec4* row1 = r.row1;
    const uint8_t* m0 = r.valid0;
    const uint8_t* m1 = r.valid1;
    PullCounts counts;
    for (int i = i_begin; i < i_end; ++i) {
        const int x0 = 2 * i, nx = std::min(2, width - x0);
        // Four valid children (within the depth ratio): the plain mean, in the same order and
        // arithmetic as pull_pixel; alpha of the sum is ignored.
        if (nx == 2 && ny == 2 && m0[x0] && m0[x0 + 1] && m1[x0] && m1[x0 + 1]) {
            const vec4 s = vec4(0.0f) + row0[x0] + row0[x0 + 1] + row1[x0] + row1[x0 + 1];
            float dmax = 0.0f;
            bool same_layer = true;
            if (use_depth) {
                const float d[4] = {sane_depth(r.depth0[x0]), sane_depth(r.depth0[x0 + 1]),
                                    sane_depth(r.depth1[x0]), sane_depth(r.depth1[x0 + 1])};
                dmax = std::max(std::max(d[0], d[1]), std::max(d[2], d[3]));
                for (float dk : d) same_layer &= dk * kBackgroundDepthRatio >= dmax;
            }
            if (same_layer && std::isfinite(s.r) && std::isfinite(s.g) && std::isfinite(s.b)) {
                r.out[i] = vec4(vec3(s) / 4.0f, 1.0f);
                if (use_depth) r.out_depth[i] = dmax;
                r.hole_bits[i] = 0;
                continue;
            }
        }
        Child child[4];
        int n = 0;
        uint8_t hole_mask = 0;
        for (int dy = 0; dy < ny; ++dy)
            for (int dx = 0; dx < nx; ++dx) {
                const vec4& c = (dy ? row1 : row0)[x0 + dx];
                const bool ok = (dy ? m1 : m0)[x0 + dx] != 0 && finite_rgb(c);
                if (!ok) hole_mask |= uint8_t(1u << (2 * dy + dx));
                const float d = use_depth ? sane_depth((dy ? r.depth1 : r.depth0)[x0 + dx]) : 0.0f;
                child[n++] = {ok ? vec3(c) : vec3(0.0f), ok ? 1.0f : 0.0f, d};
            }
        float d;
        pull_pixel(child, n, use_depth, r.out[i], d);
        if (use_depth) r.out_depth[i] = d;
        r.hole_bits[i] = hole_mask;
        counts.holes += std::size_t(std::popcount(hole_mask));
        counts.empty += r.out[i].a < 1.0f;
    }
    return counts;
}

FillStats PullPush::fill_reference(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                                   ImageView<const float> depth) {
    check_inputs(color, valid, depth);
    FillStats stats;
    if (color.empty()) return stats;
    const bool use_depth = !depth.empty();

    std::vector<Image<vec4>> level(1, Image<vec4>(color.width, color.height));
    std::vector<Image<float>> level_d(1);  // only with depth
    if (use_depth) level_d[0].resize(color.width, color.height);
    for (int y = 0; y < color.height; ++y)
        for (int x = 0; x < color.width; ++x) {
            const bool ok = valid(x, y) != 0 && finite_rgb(color(x, y));
            level[0](x, y) = ok ? vec4(vec3(color(x, y)), 1.0f) : vec4(0.0f);
            if (use_depth) level_d[0](x, y) = sane_depth(depth(x, y));
            stats.holes += !ok;
        }
    if (stats.holes == 0) return stats;
    if (stats.holes == color.pixel_count()) {
        stats.unfilled = stats.holes;
        return stats;
    }

    auto has_empty = [](const Image<vec4>& img) {
        for (std::size_t i = 0; i < img.pixel_count(); ++i)
            if (img.data()[i].a < 1.0f) return true;
        return false;
    };
    while (has_empty(level.back()) && (level.back().width() > 1 || level.back().height() > 1)) {
        const Image<vec4>& f = level.back();
        const Image<float>& fd = level_d.back();
        Image<vec4> c((f.width() + 1) / 2, (f.height() + 1) / 2);
        Image<float> cd(use_depth ? c.width() : 0, use_depth ? c.height() : 0);
        for (int j = 0; j < c.height(); ++j)
            for (int i = 0; i < c.width(); ++i) {
                Child child[4];
                int n = 0;
                for (int dy = 0; dy < 2; ++dy)
                    for (int dx = 0; dx < 2; ++dx) {
                        const int x = 2 * i + dx, y = 2 * j + dy;
                        if (x < f.width() && y < f.height())
                            child[n++] = {vec3(f(x, y)), f(x, y).a, use_depth ? fd(x, y) : 0.0f};
                    }
                float d;
                pull_pixel(child, n, use_depth, c(i, j), d);
                if (use_depth) cd(i, j) = d;
            }
        level.push_back(std::move(c));
        level_d.push_back(std::move(cd));
    }
    stats.levels = int(level.size()) - 1;
    if (stats.levels == 0 || !finish_top(level.back())) {
        stats.unfilled = stats.holes;
        return stats;
    }
    for (int s = stats.levels - 1; s >= 1; --s)
        push_rows(level[s], use_depth ? &level_d[s] : nullptr, level[s + 1],
                  use_depth ? &level_d[s + 1] : nullptr, 0, level[s].height());
    for (int y = 0; y < color.height; ++y)
        for (int x = 0; x < color.width; ++x)
            if (level[0](x, y).a == 0.0f) {
                float ud;
                const vec3 up = upsample(level[1], use_depth ? &level_d[1] : nullptr, x, y, ud);
                color(x, y) = vec4(up, color(x, y).a);
            }
    return stats;
}

FillStats PullPush::fill(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                         ImageView<const float> depth) {
    check_inputs(color, valid, depth);
    FillStats stats;
    if (color.empty()) return stats;
    const bool use_depth = !depth.empty();
    const int width = color.width, height = color.height;

    if (width == 1 && height == 1) {
        stats.holes = stats.unfilled = (valid(0, 0) == 0 || !finite_rgb(color(0, 0)));
        return stats;
    }

    // Scratch: every level down to 1x1, kept while the size stays the same.
    {
        int w = width, h = height;
        std::size_t n = 0;
        for (; w > 1 || h > 1; ++n) {
            w = (w + 1) / 2;
            h = (h + 1) / 2;
            if (n < color_levels_.size() && color_levels_[n].width() == w &&
                color_levels_[n].height() == h)
                continue;
            color_levels_.resize(n + 1);
            color_levels_[n].resize(w, h);
        }
        color_levels_.resize(n);
        depth_levels_.resize(use_depth ? n : 0);
        for (std::size_t s = 0; s < depth_levels_.size(); ++s)
            if (depth_levels_[s].width() != color_levels_[s].width() ||
                depth_levels_[s].height() != color_levels_[s].height())
                depth_levels_[s].resize(color_levels_[s].width(), color_levels_[s].height());
        if (hole_bits_.width() != color_levels_[0].width() ||
            hole_bits_.height() != color_levels_[0].height())
            hole_bits_.resize(color_levels_[0].width(), color_levels_[0].height());
    }
    auto depth_at = [&](std::size_t s) { return use_depth ? &depth_levels_[s] : nullptr; };

    // Pull from the image into level 1, recording which pixels are holes.
    std::atomic<std::size_t> holes{0}, empty{0};
    {
        Image<vec4>& c1 = color_levels_[0];
        parallel_for(
            0, c1.height(),
            [&](int j0, int j1) {
                std::size_t count = 0, empty_count = 0;
                for (int j = j0; j < j1; ++j) {
                    const int y0 = 2 * j, ny = std::min(2, height - y0);
                    const vec4* row0 = color.row(y0);
                    const vec4* row1 = color.row(y0 + ny - 1);
                    const uint8_t* m0 = valid.row(y0);
                    const uint8_t* m1 = valid.row(y0 + ny - 1);
                    vec4* out = &c1(0, j);
                    uint8_t* bits = &hole_bits_(0, j);
                    float* out_d = use_depth ? &depth_levels_[0](0, j) : nullptr;
                    const PullCounts counts =
                        pull_row({.row0 = row0,
                                  .row1 = row1,
                                  .valid0 = m0,
                                  .valid1 = m1,
                                  .depth0 = use_depth ? depth.row(y0) : nullptr,
                                  .depth1 = use_depth ? depth.row(y0 + ny - 1) : nullptr,
                                  .fine_width = width,
                                  .rows = ny,
                                  .out = out,
                                  .out_depth = out_d,
                                  .hole_bits = bits});
                    count += counts.holes;
                    empty_count += counts.empty;
                }
                holes += count;
                empty += empty_count;
            },
            grain_rows(width));
    }
    stats.holes = holes.load();
    if (stats.holes == 0) return stats;
    if (stats.holes == std::size_t(width) * std::size_t(height)) {
        stats.unfilled = stats.holes;
        return stats;
    }

    // Pull the coarser levels until one has no empty pixel.
    std::size_t top = 0;
    while (top + 1 < color_levels_.size() && empty.load() > 0) {
        empty = 0;
        const Image<vec4>& f = color_levels_[top];
        const Image<float>* fd = depth_at(top);
        Image<vec4>& c = color_levels_[top + 1];
        Image<float>* cd = depth_at(top + 1);
        parallel_for(
            0, c.height(),
            [&](int j0, int j1) {
                std::size_t empty_count = 0;
                for (int j = j0; j < j1; ++j) {
                    const int y0 = 2 * j, y1 = std::min(y0 + 1, f.height() - 1);
                    empty_count += pull_level_row({.row0 = &f(0, y0),
                                                   .row1 = &f(0, y1),
                                                   .depth0 = fd ? &(*fd)(0, y0) : nullptr,
                                                   .depth1 = fd ? &(*fd)(0, y1) : nullptr,
                                                   .fine_width = f.width(),
                                                   .rows = y1 - y0 + 1,
                                                   .out = &c(0, j),
                                                   .out_depth = cd ? &(*cd)(0, j) : nullptr});
                }
                empty += empty_count;
            },
            grain_rows(c.width()));
        ++top;
    }
    stats.levels = int(top) + 1;
    if (!finish_top(color_levels_[top])) {
        stats.unfilled = stats.holes;
        return stats;
    }

    // Push back down; level 0 writes only the holes its hole bits name.
    for (std::size_t s = top; s-- > 0;) {
        Image<vec4>& f = color_levels_[s];
        parallel_for(
            0, f.height(),
            [&](int y0, int y1) {
                push_rows(f, depth_at(s), color_levels_[s + 1], depth_at(s + 1), y0, y1);
            },
            grain_rows(f.width()));
    }
    const Image<vec4>& c1 = color_levels_[0];
    const Image<float>* d1 = depth_at(0);
    parallel_for(
        0, hole_bits_.height(),
        [&](int j0, int j1) {
            for (int j = j0; j < j1; ++j) {
                const uint8_t* bits = &hole_bits_(0, j);
                for (int i = 0; i < hole_bits_.width(); ++i) {
                    if (!bits[i]) continue;
                    for (int b = 0; b < 4; ++b)
                        if (bits[i] & (1u << b)) {
                            const int x = 2 * i + (b & 1), y = 2 * j + (b >> 1);
                            float ud;
                            color(x, y) = vec4(upsample(c1, d1, x, y, ud), color(x, y).a);
                        }
                }
            }
        },
        grain_rows(2 * width));
    return stats;
}

}  // namespace reprise::warp
