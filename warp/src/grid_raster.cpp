// Rasterising grid cells: two triangles per cell, integer edge functions on 1/256-px vertices,
// attributes (depth, source position, motion) interpolated linearly, a depth test, and a
// bilinear colour lookup in the source.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "grid_internal.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace reprise::warp::grid {

namespace {

// One attribute as a plane over a triangle: value = at_a + gx (x - a.x) + gy (y - a.y), kept
// within the vertices' range [lo, hi] against rounding.
struct Plane {
    float at_a, gx, gy, lo, hi;
};

struct Edge {
    int64_t value;  // at the first pixel centre of the current row: inside when >= 0
    int64_t step_x, step_y;
};

// Every edge is pushed out by kOverlap / kSubpixel pixels (measured along its major axis):
// neighbouring cells overlap slightly and the depth test decides there. That closes the
// hairline cracks that T-junctions between cells of different sizes and the rounding of
// vertices would otherwise leave; pixel centres half a pixel inside a cell are unaffected.
Edge edge(const Vertex& a, const Vertex& b, int64_t px, int64_t py) {
    const int64_t dx = int64_t(b.x) - a.x, dy = int64_t(b.y) - a.y;
    const int64_t push = kOverlap * std::max(dx < 0 ? -dx : dx, dy < 0 ? -dy : dy);
    return {dx * (py - a.y) - dy * (px - a.x) + push, -dy * kSubpixel, dx * kSubpixel};
}

struct Triangle {
    Edge e[3];
    Plane z, sx, sy, mx, my;
    float ax, ay;                      // vertex a, pixels
    float sx_lo, sx_hi, sy_lo, sy_hi;  // source positions kept where taps need no clamping
};

class Raster {
  public:
    Raster(ImageView<const glm::vec4> source, const Band& band, bool simd)
        : src_(source), band_(band), motion_(!band.view.motion.empty()), simd_(simd) {}

    void cell(const Cell& c) const {
        triangle(c.v[0], c.v[1], c.v[2]);
        triangle(c.v[0], c.v[2], c.v[3]);
    }

  private:
    void triangle(const Vertex& a, const Vertex& b_in, const Vertex& c_in) const {
        const Vertex* b = &b_in;
        const Vertex* c = &c_in;
        int64_t area = (int64_t(b->x) - a.x) * (int64_t(c->y) - a.y) -
                       (int64_t(b->y) - a.y) * (int64_t(c->x) - a.x);
        if (area <= 0) {
            if (area == 0) return;
            std::swap(b, c);  // fold-overs arrive turned over
            area = -area;
        }
        const int y_begin = band_.y0, y_end = band_.y0 + band_.view.color.height;
        const int x_lo = std::max(0, first_centre(int64_t(std::min({a.x, b->x, c->x})) - kOverlap));
        const int x_hi = std::min(band_.view.color.width - 1,
                                  last_centre(int64_t(std::max({a.x, b->x, c->x})) + kOverlap));
        const int y_lo =
            std::max(y_begin, first_centre(int64_t(std::min({a.y, b->y, c->y})) - kOverlap));
        const int y_hi =
            std::min(y_end - 1, last_centre(int64_t(std::max({a.y, b->y, c->y})) + kOverlap));
        if (x_lo > x_hi || y_lo > y_hi) return;

        Triangle t;
        const int64_t px = int64_t(x_lo) * kSubpixel + kSubpixel / 2,
                      py = int64_t(y_lo) * kSubpixel + kSubpixel / 2;
        t.e[0] = edge(a, *b, px, py);
        t.e[1] = edge(*b, *c, px, py);
        t.e[2] = edge(*c, a, px, py);

        const float scale = 1.0f / kSubpixel;
        const float e1x = float(b->x - a.x) * scale, e1y = float(b->y - a.y) * scale;
        const float e2x = float(c->x - a.x) * scale, e2y = float(c->y - a.y) * scale;
        // Gradients rounded once from double, so that exact quotients (1 for an unscaled
        // source position) stay exact.
        const double inverse_det = 1.0 / (double(area) * (double(scale) * scale));
        auto plane = [&](float va, float vb, float vc) {
            const float d1 = vb - va, d2 = vc - va;
            return Plane{va, float(double(d1 * e2y - d2 * e1y) * inverse_det),
                         float(double(d2 * e1x - d1 * e2x) * inverse_det), std::min({va, vb, vc}),
                         std::max({va, vb, vc})};
        };
        t.z = plane(a.z, b->z, c->z);
        t.sx = plane(a.sx, b->sx, c->sx);
        t.sy = plane(a.sy, b->sy, c->sy);
        if (motion_) {
            t.mx = plane(a.mx, b->mx, c->mx);
            t.my = plane(a.my, b->my, c->my);
        } else {
            t.mx = t.my = Plane{};
        }
        t.ax = float(a.x) * scale;
        t.ay = float(a.y) * scale;
        // A position within half a pixel of the border reads the border pixel either way.
        t.sx_lo = std::max(t.sx.lo, 0.5f);
        t.sx_hi = std::min(t.sx.hi, float(src_.width) - 0.5f);
        t.sy_lo = std::max(t.sy.lo, 0.5f);
        t.sy_hi = std::min(t.sy.hi, float(src_.height) - 0.5f);

        const bool wide = x_hi - x_lo >= 8;
        float inverse_step[3] = {};
        if (wide)
            for (int k = 0; k < 3; ++k)
                inverse_step[k] = t.e[k].step_x ? -1.0f / float(t.e[k].step_x) : 0.0f;
        for (int y = y_lo; y <= y_hi; ++y) {
            auto inside = [&](int x) {
                const int64_t k = x - x_lo;
                return ((t.e[0].value + t.e[0].step_x * k) | (t.e[1].value + t.e[1].step_x * k) |
                        (t.e[2].value + t.e[2].step_x * k)) >= 0;
            };
            int x_first = x_lo, x_last = x_hi;
            if (wide) {
                // The row's span estimated in floating point, a pixel wider each side.
                const float room = float(x_hi - x_lo) + 2.0f;
                for (int k = 0; k < 3; ++k) {
                    const Edge& e = t.e[k];
                    if (e.step_x == 0) {
                        if (e.value < 0) x_first = x_hi + 1;
                        continue;
                    }
                    const float bound = std::clamp(float(e.value) * inverse_step[k], -2.0f, room);
                    if (e.step_x > 0)
                        x_first = std::max(x_first, x_lo + int(std::floor(bound)) - 1);
                    else
                        x_last = std::min(x_last, x_lo + int(std::ceil(bound)) + 1);
                }
            }
            // The exact span: the pixels inside a convex triangle are contiguous in a row.
            while (x_first <= x_last && !inside(x_first)) ++x_first;
            while (x_last > x_first && !inside(x_last)) --x_last;
            if (x_first <= x_last) {
                while (x_first > x_lo && inside(x_first - 1)) --x_first;
                while (x_last < x_hi && inside(x_last + 1)) ++x_last;
                span(t, x_first, x_last, y);
            }
            for (Edge& e : t.e) e.value += e.step_y;
        }
    }

    // Per pixel k of a span, every attribute is start + gradient * k, clamped the way SSE's
    // max-then-min does it (NaN gives the lower bound), so that both kernels agree to the bit.
    static float clamp_like_sse(float v, float lo, float hi) {
        v = v > lo ? v : lo;
        return v < hi ? v : hi;
    }

    struct SpanStart {
        float z, sx, sy, mx, my;
    };
    static SpanStart span_start(const Triangle& t, int x_first, int y) {
        const float ox = float(x_first) + 0.5f - t.ax, oy = float(y) + 0.5f - t.ay;
        auto at = [&](const Plane& p) { return p.at_a + p.gx * ox + p.gy * oy; };
        return {at(t.z), at(t.sx), at(t.sy), at(t.mx), at(t.my)};
    }

    void span(const Triangle& t, int x_first, int x_last, int y) const {
#if defined(__SSE2__)
        if (simd_) return span_sse2(t, x_first, x_last, y);
#endif
        const SpanStart s = span_start(t, x_first, y);
        const int row = y - band_.y0;
        float* depth = band_.view.depth.row(row);
        uint8_t* covered = band_.view.covered.row(row);
        glm::vec4* color = band_.view.color.row(row);
        glm::vec2* motion = motion_ ? band_.view.motion.row(row) : nullptr;
        const int last_column = src_.width - 1, last_row = src_.height - 1;
        for (int x = x_first; x <= x_last; ++x) {
            const float k = float(x - x_first);
            const float zc = clamp_like_sse(s.z + t.z.gx * k, t.z.lo, t.z.hi);
            if (!(zc < depth[x])) continue;
            depth[x] = zc;
            covered[x] = 1;
            // Positions are >= 0.5 here, so truncation is floor.
            const float fx = clamp_like_sse(s.sx + t.sx.gx * k, t.sx_lo, t.sx_hi) - 0.5f;
            const float fy = clamp_like_sse(s.sy + t.sy.gx * k, t.sy_lo, t.sy_hi) - 0.5f;
            const int x0 = int(fx), y0 = int(fy);
            const float wx = fx - float(x0), wy = fy - float(y0);
            const glm::vec4* r0 = src_.row(y0) + x0;
            const glm::vec4* r1 = y0 < last_row ? r0 + src_.stride : r0;
            const int dx = x0 < last_column ? 1 : 0;
            const glm::vec4 top = r0[0] + (r0[dx] - r0[0]) * wx;
            const glm::vec4 bottom = r1[0] + (r1[dx] - r1[0]) * wx;
            color[x] = top + (bottom - top) * wy;
            if (motion)
                motion[x] = {clamp_like_sse(s.mx + t.mx.gx * k, t.mx.lo, t.mx.hi),
                             clamp_like_sse(s.my + t.my.gx * k, t.my.lo, t.my.hi)};
        }
    }

#if defined(__SSE2__)
    // Four pixels a step: attributes, depth test and tap positions in vector lanes, the taps of
    // the pixels that pass one by one. Reads (and rewrites unchanged) up to three depths past
    // the span: band scratch rows are padded for it.
    void span_sse2(const Triangle& t, int x_first, int x_last, int y) const {
        const SpanStart s = span_start(t, x_first, y);
        const int row = y - band_.y0;
        float* depth = band_.view.depth.row(row) + x_first;
        uint8_t* covered = band_.view.covered.row(row) + x_first;
        glm::vec4* color = band_.view.color.row(row) + x_first;
        glm::vec2* motion = motion_ ? band_.view.motion.row(row) + x_first : nullptr;
        const int last_column = src_.width - 1, last_row = src_.height - 1;
        const int n = x_last - x_first + 1;
        const __m128 lanes = _mm_setr_ps(0.0f, 1.0f, 2.0f, 3.0f), count = _mm_set1_ps(float(n));
        const __m128 z0 = _mm_set1_ps(s.z), gz = _mm_set1_ps(t.z.gx);
        const __m128 z_lo = _mm_set1_ps(t.z.lo), z_hi = _mm_set1_ps(t.z.hi);
        const __m128 sx0 = _mm_set1_ps(s.sx), gsx = _mm_set1_ps(t.sx.gx);
        const __m128 sy0 = _mm_set1_ps(s.sy), gsy = _mm_set1_ps(t.sy.gx);
        const __m128 sx_lo = _mm_set1_ps(t.sx_lo), sx_hi = _mm_set1_ps(t.sx_hi);
        const __m128 sy_lo = _mm_set1_ps(t.sy_lo), sy_hi = _mm_set1_ps(t.sy_hi);
        const __m128 half = _mm_set1_ps(0.5f);
        alignas(16) int x0s[4], y0s[4];
        alignas(16) float wxs[4], wys[4], mxs[4], mys[4];
        for (int k = 0; k < n; k += 4) {
            const __m128 kk = _mm_add_ps(_mm_set1_ps(float(k)), lanes);
            const __m128 zc =
                _mm_min_ps(_mm_max_ps(_mm_add_ps(z0, _mm_mul_ps(gz, kk)), z_lo), z_hi);
            const __m128 d = _mm_loadu_ps(depth + k);
            const __m128 pass = _mm_and_ps(_mm_cmplt_ps(zc, d), _mm_cmplt_ps(kk, count));
            int mask = _mm_movemask_ps(pass);
            if (!mask) continue;
            _mm_storeu_ps(depth + k, _mm_or_ps(_mm_and_ps(pass, zc), _mm_andnot_ps(pass, d)));
            const __m128 fx = _mm_sub_ps(
                _mm_min_ps(_mm_max_ps(_mm_add_ps(sx0, _mm_mul_ps(gsx, kk)), sx_lo), sx_hi), half);
            const __m128 fy = _mm_sub_ps(
                _mm_min_ps(_mm_max_ps(_mm_add_ps(sy0, _mm_mul_ps(gsy, kk)), sy_lo), sy_hi), half);
            const __m128i x0 = _mm_cvttps_epi32(fx), y0 = _mm_cvttps_epi32(fy);
            _mm_store_si128(reinterpret_cast<__m128i*>(x0s), x0);
            _mm_store_si128(reinterpret_cast<__m128i*>(y0s), y0);
            _mm_store_ps(wxs, _mm_sub_ps(fx, _mm_cvtepi32_ps(x0)));
            _mm_store_ps(wys, _mm_sub_ps(fy, _mm_cvtepi32_ps(y0)));
            if (motion) {
                const __m128 mx =
                    _mm_add_ps(_mm_set1_ps(s.mx), _mm_mul_ps(_mm_set1_ps(t.mx.gx), kk));
                const __m128 my =
                    _mm_add_ps(_mm_set1_ps(s.my), _mm_mul_ps(_mm_set1_ps(t.my.gx), kk));
                _mm_store_ps(
                    mxs, _mm_min_ps(_mm_max_ps(mx, _mm_set1_ps(t.mx.lo)), _mm_set1_ps(t.mx.hi)));
                _mm_store_ps(
                    mys, _mm_min_ps(_mm_max_ps(my, _mm_set1_ps(t.my.lo)), _mm_set1_ps(t.my.hi)));
            }
            while (mask) {
                const int i = __builtin_ctz(unsigned(mask));
                mask &= mask - 1;
                covered[k + i] = 1;
                const glm::vec4* r0 = src_.row(y0s[i]) + x0s[i];
                const glm::vec4* r1 = y0s[i] < last_row ? r0 + src_.stride : r0;
                const int dx = x0s[i] < last_column ? 1 : 0;
                const __m128 wx = _mm_set1_ps(wxs[i]), wy = _mm_set1_ps(wys[i]);
                const __m128 a = _mm_loadu_ps(&r0[0].x), b = _mm_loadu_ps(&r0[dx].x);
                const __m128 c = _mm_loadu_ps(&r1[0].x), e = _mm_loadu_ps(&r1[dx].x);
                const __m128 top = _mm_add_ps(a, _mm_mul_ps(_mm_sub_ps(b, a), wx));
                const __m128 bottom = _mm_add_ps(c, _mm_mul_ps(_mm_sub_ps(e, c), wx));
                _mm_storeu_ps(&color[k + i].x,
                              _mm_add_ps(top, _mm_mul_ps(_mm_sub_ps(bottom, top), wy)));
                if (motion) motion[k + i] = {mxs[i], mys[i]};
            }
        }
    }
#endif

    ImageView<const glm::vec4> src_;
    const Band& band_;
    bool motion_;
    bool simd_;
};

}  // namespace

void draw_cell(ImageView<const glm::vec4> source, const Cell& c, const Band& band, bool simd) {
    int lo = c.v[0].y, hi = c.v[0].y;
    for (const Vertex& v : c.v) {
        lo = std::min(lo, v.y);
        hi = std::max(hi, v.y);
    }
    if (first_centre(int64_t(lo) - kOverlap) >= band.y0 + band.view.color.height ||
        last_centre(int64_t(hi) + kOverlap) < band.y0)
        return;
    Raster(source, band, simd).cell(c);
}

}  // namespace reprise::warp::grid
