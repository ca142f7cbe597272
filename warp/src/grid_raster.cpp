// Rasterising grid cells: two triangles per cell, integer edge functions on 1/256-px vertices,
// attributes (depth, source position, motion) interpolated linearly, a depth test, and a
// bilinear (or bicubic) colour lookup in the source. Compiled once per Highway target and chosen
// at run time: from AVX2 on, the bilinear colour of two pixels is fetched a 256-bit vector at a
// time, and the bicubic colour's weights are computed four pixels at a time (bicubic-inl.h, the
// reverse warp's refetch shares it); same bits as the scalar reference either way.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "grid_internal.hpp"
#include "reprise/warp/sample.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#include <immintrin.h>
#endif

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "grid_raster.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "bicubic-inl.h"

HWY_BEFORE_NAMESPACE();
namespace reprise::warp::grid::HWY_NAMESPACE {

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

#if defined(__SSE2__)
// A triangle's gradients and bounds in every lane, for the vector kernel.
struct VectorTriangle {
    __m128 gz, z_lo, z_hi, depth_lo, depth_hi, stretch_scale, stretch_last;
    __m128 gsx, sx_lo, sx_hi, gsy, sy_lo, sy_hi;
    __m128 gmx, mx_lo, mx_hi, gmy, my_lo, my_hi;
    __m128i stride, last_column, last_row;
};
#endif

struct Triangle {
    Edge e[3];
    Plane z, sx, sy, mx, my;  // z: of 1/depth when `perspective`, else of depth
    bool perspective;
    // A stretched triangle (kCoveredStretched) marks the pixels more than a pixel from both its
    // nearest and its farthest vertices: (z - z_lo) * stretch_scale px from the nearest, of
    // stretch_span px. Within a pixel of either end lies what the source saw (an anti-aliased
    // edge); each of its pixels is marked 1 like every pixel of other triangles.
    bool stretched;
    float stretch_scale, stretch_span;
    float z_lo, z_hi;                  // the vertices' depth range (perspective)
    float ax, ay;                      // vertex a, pixels
    float sx_lo, sx_hi, sy_lo, sy_hi;  // source positions kept where taps need no clamping
#if defined(__SSE2__)
    VectorTriangle vec;  // filled for the vector kernel only
#endif
};

class Raster {
public:
    Raster(ImageView<const glm::vec4> source, const Band& band, bool simd, bool bicubic)
        : src_(source),
          band_(band),
          motion_(!band.view.motion.empty()),
          simd_(simd),
          bicubic_(bicubic) {}

    void cell(const Cell& c) const {
        triangle(c.v[0], c.v[1], c.v[2], c.perspective, c.coverage[0]);
        triangle(c.v[0], c.v[2], c.v[3], c.perspective, c.coverage[1]);
    }

private:
    void triangle(const Vertex& a, const Vertex& b_in, const Vertex& c_in, bool perspective,
                  uint8_t coverage) const {
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
        t.perspective = perspective;
        t.stretched = coverage == kCoveredStretched;
        t.stretch_span = t.stretch_scale = 0.0f;
        if (t.stretched) {
            const float z_lo = std::min({a.z, b->z, c->z}), z_hi = std::max({a.z, b->z, c->z});
            const float ab = std::hypot(e1x, e1y), ac = std::hypot(e2x, e2y);
            const float bc = std::hypot(e2x - e1x, e2y - e1y);
            t.stretch_span = std::max({ab, ac, bc});
            t.stretch_scale = t.stretch_span / (z_hi - z_lo);
        }
        if (perspective) {
            // 1/z is affine in screen space on a plane; depth 0 stands in as 1e-30.
            auto inverse = [](float z) { return 1.0f / std::max(z, 1e-30f); };
            t.z = plane(inverse(a.z), inverse(b->z), inverse(c->z));
            t.z_lo = std::min({a.z, b->z, c->z});
            t.z_hi = std::max({a.z, b->z, c->z});
        } else {
            t.z = plane(a.z, b->z, c->z);
            t.z_lo = t.z_hi = 0.0f;
        }
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

#if defined(__SSE2__)
        if (simd_) {
            VectorTriangle& v = t.vec;
            v.gz = _mm_set1_ps(t.z.gx);
            v.z_lo = _mm_set1_ps(t.z.lo);
            v.z_hi = _mm_set1_ps(t.z.hi);
            v.depth_lo = _mm_set1_ps(t.z_lo);
            v.depth_hi = _mm_set1_ps(t.z_hi);
            v.stretch_scale = _mm_set1_ps(t.stretch_scale);
            v.stretch_last = _mm_set1_ps(t.stretch_span - 1.0f);
            v.gsx = _mm_set1_ps(t.sx.gx);
            v.sx_lo = _mm_set1_ps(t.sx_lo);
            v.sx_hi = _mm_set1_ps(t.sx_hi);
            v.gsy = _mm_set1_ps(t.sy.gx);
            v.sy_lo = _mm_set1_ps(t.sy_lo);
            v.sy_hi = _mm_set1_ps(t.sy_hi);
            v.gmx = _mm_set1_ps(t.mx.gx);
            v.mx_lo = _mm_set1_ps(t.mx.lo);
            v.mx_hi = _mm_set1_ps(t.mx.hi);
            v.gmy = _mm_set1_ps(t.my.gx);
            v.my_lo = _mm_set1_ps(t.my.lo);
            v.my_hi = _mm_set1_ps(t.my.hi);
            v.stride = _mm_set1_epi32(int(src_.stride));
            v.last_column = _mm_set1_epi32(src_.width - 1);
            v.last_row = _mm_set1_epi32(src_.height - 1);
        }
#endif
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

    static uint8_t coverage_at(const Triangle& t, float zc) {
        if (!t.stretched) return 1;
        const float from_near = (zc - t.z.lo) * t.stretch_scale;
        return from_near >= 1.0f && from_near <= t.stretch_span - 1.0f ? kCoveredStretched : 1;
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
            float zc = clamp_like_sse(s.z + t.z.gx * k, t.z.lo, t.z.hi);
            if (t.perspective) zc = clamp_like_sse(1.0f / zc, t.z_lo, t.z_hi);
            if (!(zc < depth[x])) continue;
            depth[x] = zc;
            covered[x] = coverage_at(t, zc);
            // Positions are >= 0.5 here, so truncation is floor.
            const float fx = clamp_like_sse(s.sx + t.sx.gx * k, t.sx_lo, t.sx_hi) - 0.5f;
            const float fy = clamp_like_sse(s.sy + t.sy.gx * k, t.sy_lo, t.sy_hi) - 0.5f;
            if (bicubic_) {
                color[x] = bicubic_fetch(src_, fx + 0.5f, fy + 0.5f);
                if (motion)
                    motion[x] = {clamp_like_sse(s.mx + t.mx.gx * k, t.mx.lo, t.mx.hi),
                                 clamp_like_sse(s.my + t.my.gx * k, t.my.lo, t.my.hi)};
                continue;
            }
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
    // Four pixels a step: attributes, depth test, tap offsets and the depth, motion and coverage
    // stores in vector lanes; the colour of each pixel that passes on its own. Reads (and
    // rewrites unchanged) up to three pixels past the span: band scratch rows are padded for it.
    void span_sse2(const Triangle& t, int x_first, int x_last, int y) const {
        const SpanStart s = span_start(t, x_first, y);
        const int row = y - band_.y0;
        float* depth = band_.view.depth.row(row) + x_first;
        uint8_t* covered = band_.view.covered.row(row) + x_first;
        glm::vec4* color = band_.view.color.row(row) + x_first;
        glm::vec2* motion = motion_ ? band_.view.motion.row(row) + x_first : nullptr;
        const glm::vec4* source = src_.data;
        const int n = x_last - x_first + 1;
        const __m128 lanes = _mm_setr_ps(0.0f, 1.0f, 2.0f, 3.0f), count = _mm_set1_ps(float(n));
        const __m128 half = _mm_set1_ps(0.5f), one = _mm_set1_ps(1.0f);
        const __m128 z0 = _mm_set1_ps(s.z), sx0 = _mm_set1_ps(s.sx), sy0 = _mm_set1_ps(s.sy);
        const __m128 mx0 = _mm_set1_ps(s.mx), my0 = _mm_set1_ps(s.my);
        const VectorTriangle& v = t.vec;
        alignas(16) int offsets[4], right[4], below[4];
        alignas(16) float wxs[4], wys[4];
        for (int k = 0; k < n; k += 4) {
            const __m128 kk = _mm_add_ps(_mm_set1_ps(float(k)), lanes);
            __m128 zc =
                _mm_min_ps(_mm_max_ps(_mm_add_ps(z0, _mm_mul_ps(v.gz, kk)), v.z_lo), v.z_hi);
            if (t.perspective)
                zc = _mm_min_ps(_mm_max_ps(_mm_div_ps(one, zc), v.depth_lo), v.depth_hi);
            const __m128 d = _mm_loadu_ps(depth + k);
            const __m128 pass = _mm_and_ps(_mm_cmplt_ps(zc, d), _mm_cmplt_ps(kk, count));
            int mask = _mm_movemask_ps(pass);
            if (!mask) continue;
            _mm_storeu_ps(depth + k, _mm_or_ps(_mm_and_ps(pass, zc), _mm_andnot_ps(pass, d)));
            {  // coverage (coverage_at) where a pixel passed
                __m128i level = _mm_set1_epi32(1);
                if (t.stretched) {
                    const __m128 from_near = _mm_mul_ps(_mm_sub_ps(zc, v.z_lo), v.stretch_scale);
                    const __m128 middle = _mm_and_ps(_mm_cmpge_ps(from_near, one),
                                                     _mm_cmple_ps(from_near, v.stretch_last));
                    level = _mm_sub_epi32(level, _mm_castps_si128(middle));  // 1 or 2
                }
                const __m128i p = _mm_and_si128(_mm_castps_si128(pass), level);
                const __m128i bytes = _mm_packus_epi16(_mm_packs_epi32(p, p), p);
                const __m128i keep = _mm_castps_si128(pass);
                const int set =
                    _mm_cvtsi128_si32(_mm_packs_epi16(_mm_packs_epi32(keep, keep), keep));
                int old;
                std::memcpy(&old, covered + k, 4);
                old = (old & ~set) | _mm_cvtsi128_si32(bytes);
                std::memcpy(covered + k, &old, 4);
            }
            if (motion) {
                const __m128 mx = _mm_min_ps(
                    _mm_max_ps(_mm_add_ps(mx0, _mm_mul_ps(v.gmx, kk)), v.mx_lo), v.mx_hi);
                const __m128 my = _mm_min_ps(
                    _mm_max_ps(_mm_add_ps(my0, _mm_mul_ps(v.gmy, kk)), v.my_lo), v.my_hi);
                const __m128 pass01 = _mm_unpacklo_ps(pass, pass),
                             pass23 = _mm_unpackhi_ps(pass, pass);
                float* m = &motion[k].x;
                const __m128 old01 = _mm_loadu_ps(m), old23 = _mm_loadu_ps(m + 4);
                _mm_storeu_ps(m, _mm_or_ps(_mm_and_ps(pass01, _mm_unpacklo_ps(mx, my)),
                                           _mm_andnot_ps(pass01, old01)));
                _mm_storeu_ps(m + 4, _mm_or_ps(_mm_and_ps(pass23, _mm_unpackhi_ps(mx, my)),
                                               _mm_andnot_ps(pass23, old23)));
            }
            const __m128 fx = _mm_sub_ps(
                _mm_min_ps(_mm_max_ps(_mm_add_ps(sx0, _mm_mul_ps(v.gsx, kk)), v.sx_lo), v.sx_hi),
                half);
            const __m128 fy = _mm_sub_ps(
                _mm_min_ps(_mm_max_ps(_mm_add_ps(sy0, _mm_mul_ps(v.gsy, kk)), v.sy_lo), v.sy_hi),
                half);
            if (bicubic_) {
                bicubic_quad(_mm_add_ps(fx, half), _mm_add_ps(fy, half), mask, color + k);
                continue;
            }
            const __m128i x0 = _mm_cvttps_epi32(fx), y0 = _mm_cvttps_epi32(fy);
            const __m128 wx4 = _mm_sub_ps(fx, _mm_cvtepi32_ps(x0));
            const __m128 wy4 = _mm_sub_ps(fy, _mm_cvtepi32_ps(y0));
            // Tap offsets in pixels: y0 * stride + x0 (SSE2 has no 32-bit lane product), the
            // right tap one further unless in the last column, the lower one a stride further
            // unless in the last row.
            const __m128i even = _mm_mul_epu32(y0, v.stride);
            const __m128i odd = _mm_mul_epu32(_mm_srli_epi64(y0, 32), v.stride);
            const __m128i rows =
                _mm_unpacklo_epi32(_mm_shuffle_epi32(even, _MM_SHUFFLE(0, 0, 2, 0)),
                                   _mm_shuffle_epi32(odd, _MM_SHUFFLE(0, 0, 2, 0)));
            _mm_store_si128(reinterpret_cast<__m128i*>(offsets), _mm_add_epi32(rows, x0));
            _mm_store_si128(reinterpret_cast<__m128i*>(right),
                            _mm_srli_epi32(_mm_cmplt_epi32(x0, v.last_column), 31));
            _mm_store_si128(reinterpret_cast<__m128i*>(below),
                            _mm_and_si128(_mm_cmplt_epi32(y0, v.last_row), v.stride));
            // The colour of pixel i: weights taken from lane i.
            auto fetch = [&](int i, __m128 wx, __m128 wy) {
                const glm::vec4* r0 = source + offsets[i];
                const glm::vec4* r1 = r0 + below[i];
                const int dx = right[i];
                const __m128 a = _mm_loadu_ps(&r0[0].x), b = _mm_loadu_ps(&r0[dx].x);
                const __m128 c = _mm_loadu_ps(&r1[0].x), e = _mm_loadu_ps(&r1[dx].x);
                const __m128 top = _mm_add_ps(a, _mm_mul_ps(_mm_sub_ps(b, a), wx));
                const __m128 bottom = _mm_add_ps(c, _mm_mul_ps(_mm_sub_ps(e, c), wx));
                _mm_storeu_ps(&color[k + i].x,
                              _mm_add_ps(top, _mm_mul_ps(_mm_sub_ps(bottom, top), wy)));
            };
#if HWY_TARGET <= HWY_AVX2
            // Two pixels a 256-bit vector when every right tap is the next pixel: its top and
            // bottom taps are one 32-byte load each.
            if (mask == 0xf &&
                _mm_movemask_ps(_mm_castsi128_ps(_mm_cmplt_epi32(x0, v.last_column))) == 0xf) {
                auto pair = [&](int i, __m128 wx_i, __m128 wx_j, __m128 wy_i, __m128 wy_j) {
                    const float* top_i = &source[offsets[i]].x;
                    const float* top_j = &source[offsets[i + 1]].x;
                    const __m256 t0 = _mm256_loadu_ps(top_i), t1 = _mm256_loadu_ps(top_j);
                    const __m256 b0 = _mm256_loadu_ps(top_i + 4 * below[i]);
                    const __m256 b1 = _mm256_loadu_ps(top_j + 4 * below[i + 1]);
                    const __m256 a = _mm256_permute2f128_ps(t0, t1, 0x20);
                    const __m256 b = _mm256_permute2f128_ps(t0, t1, 0x31);
                    const __m256 c = _mm256_permute2f128_ps(b0, b1, 0x20);
                    const __m256 e = _mm256_permute2f128_ps(b0, b1, 0x31);
                    const __m256 wx = _mm256_set_m128(wx_j, wx_i), wy = _mm256_set_m128(wy_j, wy_i);
                    const __m256 top = _mm256_add_ps(a, _mm256_mul_ps(_mm256_sub_ps(b, a), wx));
                    const __m256 bottom = _mm256_add_ps(c, _mm256_mul_ps(_mm256_sub_ps(e, c), wx));
                    _mm256_storeu_ps(
                        &color[k + i].x,
                        _mm256_add_ps(top, _mm256_mul_ps(_mm256_sub_ps(bottom, top), wy)));
                };
                pair(0, _mm_shuffle_ps(wx4, wx4, 0x00), _mm_shuffle_ps(wx4, wx4, 0x55),
                     _mm_shuffle_ps(wy4, wy4, 0x00), _mm_shuffle_ps(wy4, wy4, 0x55));
                pair(2, _mm_shuffle_ps(wx4, wx4, 0xaa), _mm_shuffle_ps(wx4, wx4, 0xff),
                     _mm_shuffle_ps(wy4, wy4, 0xaa), _mm_shuffle_ps(wy4, wy4, 0xff));
                continue;
            }
#endif
            if (mask == 0xf) {  // the common case, without bookkeeping
                fetch(0, _mm_shuffle_ps(wx4, wx4, 0x00), _mm_shuffle_ps(wy4, wy4, 0x00));
                fetch(1, _mm_shuffle_ps(wx4, wx4, 0x55), _mm_shuffle_ps(wy4, wy4, 0x55));
                fetch(2, _mm_shuffle_ps(wx4, wx4, 0xaa), _mm_shuffle_ps(wy4, wy4, 0xaa));
                fetch(3, _mm_shuffle_ps(wx4, wx4, 0xff), _mm_shuffle_ps(wy4, wy4, 0xff));
                continue;
            }
            _mm_store_ps(wxs, wx4);
            _mm_store_ps(wys, wy4);
            while (mask) {
                const int i = __builtin_ctz(unsigned(mask));
                mask &= mask - 1;
                fetch(i, _mm_set1_ps(wxs[i]), _mm_set1_ps(wys[i]));
            }
        }
    }

    // bicubic_fetch at the four positions in x, y, for the pixels in `mask`, into out[0..3]:
    // weights in vector lanes, each pixel's taps vectorised, taps past the border by the
    // reference.
    void bicubic_quad(__m128 x, __m128 y, int mask, glm::vec4* out) const {
        alignas(16) float xs[4], ys[4];
        _mm_store_ps(xs, x);
        _mm_store_ps(ys, y);
#if HWY_TARGET != HWY_SCALAR
        namespace hn = hwy::HWY_NAMESPACE;
        using warp::HWY_NAMESPACE::BicubicLanes, warp::HWY_NAMESPACE::BicubicPrepare,
            warp::HWY_NAMESPACE::BicubicSum;
        const hn::Full128<float> d4;
        BicubicLanes lanes;
        const auto inside =
            BicubicPrepare(d4, hn::Load(d4, xs), hn::Load(d4, ys), src_.width, src_.height, lanes);
        uint8_t inside_bits = 0;
        hn::StoreMaskBits(d4, inside, &inside_bits);
        while (mask) {
            const int i = __builtin_ctz(unsigned(mask));
            mask &= mask - 1;
            if ((inside_bits >> i) & 1)
                hn::StoreU(BicubicSum(src_, lanes, i), d4, &out[i].x);
            else
                out[i] = bicubic_fetch(src_, xs[i], ys[i]);
        }
#else
        while (mask) {
            const int i = __builtin_ctz(unsigned(mask));
            mask &= mask - 1;
            out[i] = bicubic_fetch(src_, xs[i], ys[i]);
        }
#endif
    }
#endif

    ImageView<const glm::vec4> src_;
    const Band& band_;
    bool motion_;
    bool simd_;
    bool bicubic_;
};

}  // namespace

void DrawCellSimd(ImageView<const glm::vec4> source, const Cell& c, const Band& band, bool simd,
                  bool bicubic) {
    int lo = c.v[0].y, hi = c.v[0].y;
    for (const Vertex& v : c.v) {
        lo = std::min(lo, v.y);
        hi = std::max(hi, v.y);
    }
    if (first_centre(int64_t(lo) - kOverlap) >= band.y0 + band.view.color.height ||
        last_centre(int64_t(hi) + kOverlap) < band.y0)
        return;
    Raster(source, band, simd, bicubic).cell(c);
}

}  // namespace reprise::warp::grid::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace reprise::warp::grid {

HWY_EXPORT(DrawCellSimd);

void draw_cell(ImageView<const glm::vec4> source, const Cell& c, const Band& band, bool simd,
               bool bicubic) {
    HWY_DYNAMIC_DISPATCH(DrawCellSimd)(source, c, band, simd, bicubic);
}

}  // namespace reprise::warp::grid
#endif
