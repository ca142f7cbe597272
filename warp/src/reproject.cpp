// Reverse reprojection with a depth and id cache-hit test (Nehab et al. 2007, §3.2).
#include "reprise/warp/reproject.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <limits>

#include "reprise/core/parallel.hpp"
#include "reprise/warp/sample.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

// Compiled once per Highway target (foreach_target.h includes this file again): the shared
// scalar part once, the row loop per target, the public functions once.
#ifndef REPRISE_WARP_REPROJECT_SHARED
#define REPRISE_WARP_REPROJECT_SHARED

namespace reprise::warp {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

enum Outcome { Hit, Offscreen, Behind, Occluded, OtherId, Invalid, OutcomeCount };

using Setup = ReprojectSetup;

Setup make_setup(const GBufferView& current, const GBufferView& previous,
                 const ReprojectOptions& options) {
    return reproject_setup(current.camera, previous.camera, current.depth.width,
                           current.depth.height, !current.id.empty() && !previous.id.empty(),
                           options);
}

// Shared by both paths so that they decide alike; `row` = ky (y + py0) + kw.
inline float expected_depth(const Setup& s, float px, float row, float z) {
    const float w = s.wz * z + s.w1;
    return w * (s.kx * px + row) + (s.kz * z + s.k1);
}

void check_contract(const GBufferView& current, const GBufferView& previous, const ConstPayload& in,
                    const Payload& out, const ImageView<uint8_t>& hit) {
    const int w = current.depth.width, h = current.depth.height;
    REPRISE_ASSERT(current.motion.width == w && current.motion.height == h);
    REPRISE_ASSERT(current.id.empty() || (current.id.width == w && current.id.height == h));
    const int pw = previous.depth.width, ph = previous.depth.height;
    REPRISE_ASSERT(previous.id.empty() || (previous.id.width == pw && previous.id.height == ph));
    REPRISE_ASSERT(in.width == pw && in.height == ph && in.channels >= 1);
    REPRISE_ASSERT(out.width == w && out.height == h && out.channels == in.channels);
    REPRISE_ASSERT(hit.empty() || (hit.width == w && hit.height == h));
    const float* out_end = out.data + (h - 1) * out.stride + std::ptrdiff_t(w) * out.channels;
    const float* in_end = in.data + (ph - 1) * in.stride + std::ptrdiff_t(pw) * in.channels;
    REPRISE_ASSERT(out_end <= in.data || in_end <= out.data);  // no reprojection in place
}

ReprojectCounts to_counts(const std::size_t* n) {
    ReprojectCounts c;
    c.hits = n[Hit];
    c.offscreen = n[Offscreen];
    c.behind = n[Behind];
    c.occluded = n[Occluded];
    c.other_id = n[OtherId];
    c.invalid = n[Invalid];
    return c;
}

// The fast path: raw row pointers, everything per frame or per row hoisted out of the loop.
struct Kernel {
    Setup s;
    int width, pw, ph, channels;
    const float* depth;
    std::ptrdiff_t depth_stride;
    const glm::vec2* motion;
    std::ptrdiff_t motion_stride;
    const uint32_t* id;
    std::ptrdiff_t id_stride;
    const float* prev_depth;
    std::ptrdiff_t prev_depth_stride;
    const uint32_t* prev_id;
    std::ptrdiff_t prev_id_stride;
    const float* in;
    std::ptrdiff_t in_stride;
    float* out;
    std::ptrdiff_t out_stride;
    uint8_t* hit;
    std::ptrdiff_t hit_stride;
};

inline bool finite(float v) { return v - v == 0.0f; }

// Bilinear over taps a, b (row 0) and c, d (row 1) of n channels; writes `dst` only when every
// channel is finite.
template <int C>
inline bool fetch(const float* a, const float* b, const float* c, const float* d, int n, float fx,
                  float fy, float* dst) {
#if defined(__SSE2__)
    if constexpr (C == 4) {
        const __m128 vfx = _mm_set1_ps(fx), vfy = _mm_set1_ps(fy);
        const __m128 va = _mm_loadu_ps(a), vb = _mm_loadu_ps(b);
        const __m128 vc = _mm_loadu_ps(c), vd = _mm_loadu_ps(d);
        const __m128 top = _mm_add_ps(va, _mm_mul_ps(_mm_sub_ps(vb, va), vfx));
        const __m128 bottom = _mm_add_ps(vc, _mm_mul_ps(_mm_sub_ps(vd, vc), vfx));
        const __m128 v = _mm_add_ps(top, _mm_mul_ps(_mm_sub_ps(bottom, top), vfy));
        const __m128 zero = _mm_sub_ps(v, v);
        if (_mm_movemask_ps(_mm_cmpunord_ps(zero, zero)) != 0) return false;
        _mm_storeu_ps(dst, v);
        return true;
    }
#endif
    if constexpr (C > 0) n = C;
    float acc = 0.0f;
    for (int k = 0; k < n; ++k) {
        const float top = a[k] + (b[k] - a[k]) * fx, bottom = c[k] + (d[k] - c[k]) * fx;
        const float v = top + (bottom - top) * fy;
        acc += v - v;
    }
    if (!finite(acc)) return false;
    for (int k = 0; k < n; ++k) {
        const float top = a[k] + (b[k] - a[k]) * fx, bottom = c[k] + (d[k] - c[k]) * fx;
        dst[k] = top + (bottom - top) * fy;
    }
    return true;
}

}  // namespace

ReprojectSetup reproject_setup(const Camera& c, const Camera& previous, int width, int height,
                               bool ids, const ReprojectOptions& options) {
    const glm::dmat4 p(c.projection);
    // Unprojection at a known depth solves a 2x2 system for (x_view, y_view); that needs a clip w
    // free of x_view and y_view, as perspective and orthographic projections have.
    const double a = p[0][0], b = p[1][0], cc = p[0][1], d = p[1][1];
    const double det = a * d - b * cc;
    const glm::dmat4 t = glm::dmat4(c.prev_view) * glm::inverse(glm::dmat4(c.view));
    const double m00 = d / det, m01 = -b / det, m10 = -cc / det, m11 = a / det;
    const double u0 = t[0][2] * m00 + t[1][2] * m10, u1 = t[0][2] * m01 + t[1][2] * m11;
    const double w = width, h = height;
    double k[7] = {-2.0 * u0 / w,
                   2.0 * u1 / h,
                   u0 - u1,
                   t[2][2] - u0 * p[2][0] - u1 * p[2][1],
                   u0 * p[3][0] + u1 * p[3][1] - t[3][2],
                   -p[2][3],
                   p[3][3]};
    bool usable = p[0][3] == 0.0 && p[1][3] == 0.0 && det != 0.0;
    for (double& v : k) {
        usable = usable && std::isfinite(v) && std::abs(v) < 1e38;
    }
    if (!usable) std::fill(std::begin(k), std::end(k), std::numeric_limits<double>::quiet_NaN());

    ReprojectSetup s{};
    s.kx = float(k[0]);
    s.ky = float(k[1]);
    s.kw = float(k[2]);
    s.kz = float(k[3]);
    s.k1 = float(k[4]);
    s.wz = float(k[5]);
    s.w1 = float(k[6]);
    const glm::vec2 j = c.jitter, pj = previous.jitter;
    s.px0 = float(0.5 + double(j.x));
    s.py0 = float(0.5 + double(j.y));
    s.qx0 = float(0.5 + double(j.x) - double(pj.x));
    s.qy0 = float(0.5 + double(j.y) - double(pj.y));
    s.tolerance = options.depth_tolerance;
    s.id_tolerance = options.id_depth_tolerance;
    s.use_ids = options.match_ids && ids;
    s.background = options.background;
    return s;
}

}  // namespace reprise::warp
#endif  // REPRISE_WARP_REPROJECT_SHARED

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "reproject.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace reprise::warp::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Rows [y_begin, y_end) with C payload channels (0: any). Everything the loop reads is copied
// into locals first: the float stores to `out` could otherwise alias them.
template <int C>
void reproject_rows(const Kernel& kernel, int y_begin, int y_end, int step, std::size_t* counts) {
    const Setup s = kernel.s;
    const int width = kernel.width, pw = kernel.pw, ph = kernel.ph;
    const int n = C > 0 ? C : kernel.channels;
    const float fpw = float(pw), fph = float(ph);
    const float* const depth = kernel.depth;
    const glm::vec2* const motion = kernel.motion;
    const uint32_t* const id = kernel.id;
    const float* const prev_depth = kernel.prev_depth;
    const uint32_t* const prev_id = kernel.prev_id;
    const float* const in = kernel.in;
    float* const out = kernel.out;
    uint8_t* const hit = kernel.hit;
    const std::ptrdiff_t depth_stride = kernel.depth_stride, motion_stride = kernel.motion_stride,
                         id_stride = kernel.id_stride, prev_depth_stride = kernel.prev_depth_stride,
                         prev_id_stride = kernel.prev_id_stride, in_stride = kernel.in_stride,
                         out_stride = kernel.out_stride, hit_stride = kernel.hit_stride;
    const bool use_ids = s.use_ids, background_hits = s.background;
    std::size_t hits = 0;

    auto record = [&](int x, Outcome o, uint8_t* hrow) {
        if (o == Hit)
            ++hits;
        else
            ++counts[o];
        if (hrow) hrow[x] = o == Hit;
    };
    for (int y = y_begin; y < y_end; y += step) {
        const float* const zr = depth + y * depth_stride;
        const glm::vec2* const mr = motion + y * motion_stride;
        const uint32_t* const ir = use_ids ? id + y * id_stride : nullptr;
        float* const orow = out + y * out_stride;
        uint8_t* const hrow = hit ? hit + y * hit_stride : nullptr;
        const float row = s.ky * (float(y) + s.py0) + s.kw;
        const float qy_row = float(y) + s.qy0;
        auto classify = [&](int x) -> Outcome {
            const float z = zr[x], mx = mr[x].x, my = mr[x].y;
            if (!finite(mx) || !finite(my)) return Invalid;
            float z_expected = 0.0f;
            const bool background = !finite(z);
            if (!background) {
                z_expected = expected_depth(s, float(x) + s.px0, row, z);
                if (!finite(z_expected)) return Invalid;
                if (z_expected <= 0.0f) return Behind;
            } else if (!(background_hits && z == kInf)) {
                return Invalid;
            }
            const float qx = (float(x) + s.qx0) + mx, qy = qy_row + my;
            if (!(qx >= 0.0f && qy >= 0.0f && qx <= fpw && qy <= fph)) return Offscreen;

            // floor() by truncation and correction: exact, and no libm call without SSE4.1.
            const float sx = qx - 0.5f, sy = qy - 0.5f;
            int ix = int(sx), iy = int(sy);
            ix -= sx < float(ix);
            iy -= sy < float(iy);
            const float fx = sx - float(ix), fy = sy - float(iy);
            const int x0 = std::clamp(ix, 0, pw - 1), y0 = std::clamp(iy, 0, ph - 1);
            const int x1 = fx == 0.0f ? x0 : std::min(ix + 1, pw - 1);
            const int y1 = fy == 0.0f ? y0 : std::min(iy + 1, ph - 1);

            bool ids_agree = true;
            if (use_ids) {
                const uint32_t* i0 = prev_id + y0 * prev_id_stride;
                const uint32_t* i1 = prev_id + y1 * prev_id_stride;
                const uint32_t me = ir[x];
                ids_agree = ((i0[x0] ^ me) | (i0[x1] ^ me) | (i1[x0] ^ me) | (i1[x1] ^ me)) == 0;
            }
            const float* d0 = prev_depth + y0 * prev_depth_stride;
            const float* d1 = prev_depth + y1 * prev_depth_stride;
            const float a = d0[x0], b = d0[x1], c = d1[x0], d = d1[x1];
            if (background) {
                if (!(a == kInf && b == kInf && c == kInf && d == kInf)) return Occluded;
            } else {
                if (!((a - a) + (b - b) + (c - c) + (d - d) == 0.0f)) return Occluded;
                const float top = a + (b - a) * fx, bottom = c + (d - c) * fx;
                const float z_previous = top + (bottom - top) * fy;
                const float tolerance = use_ids && ids_agree ? s.id_tolerance : s.tolerance;
                if (!(std::abs(z_expected - z_previous) <= tolerance * z_expected)) return Occluded;
            }
            if (!ids_agree) return OtherId;
            const float* r0 = in + y0 * in_stride;
            const float* r1 = in + y1 * in_stride;
            const std::ptrdiff_t c0 = std::ptrdiff_t(x0) * n, c1 = std::ptrdiff_t(x1) * n;
            if (!fetch<C>(r0 + c0, r0 + c1, r1 + c0, r1 + c1, n, fx, fy,
                          orow + std::ptrdiff_t(x) * n))
                return Invalid;
            return Hit;
        };

        int x = 0;
        if (step > 1) {
            for (; x < width; x += step) record(x, classify(x), hrow);
            continue;
        }
#if HWY_TARGET != HWY_SCALAR
        // Lanes() pixels at a time: the same arithmetic lane by lane (so the same bits as the
        // scalar code), the taps gathered. Blocks with any pixel that is invalid, behind or
        // offscreen go to the scalar code.
        const hn::ScalableTag<float> df;
        const hn::RebindToSigned<decltype(df)> di;
        using VF = hn::Vec<decltype(df)>;
        using VI = hn::Vec<decltype(di)>;
        const int lanes = int(hn::Lanes(df));
        const VF zero = hn::Zero(df), inf = hn::Set(df, kInf), half = hn::Set(df, 0.5f);
        // Iota(d, x) in the loop would store its lanes and load them back (Highway 1.0): a stall.
        const VF lane_numbers = hn::Iota(df, 0.0f);
        const VF v_kx = hn::Set(df, s.kx), v_kz = hn::Set(df, s.kz), v_k1 = hn::Set(df, s.k1);
        const VF v_wz = hn::Set(df, s.wz), v_w1 = hn::Set(df, s.w1), v_row = hn::Set(df, row);
        const VF v_px0 = hn::Set(df, s.px0), v_qx0 = hn::Set(df, s.qx0), v_qy = hn::Set(df, qy_row);
        const VF v_fpw = hn::Set(df, fpw), v_fph = hn::Set(df, fph);
        const VF v_tol = hn::Set(df, s.tolerance), v_id_tol = hn::Set(df, s.id_tolerance);
        const VI v_pw1 = hn::Set(di, pw - 1), v_ph1 = hn::Set(di, ph - 1), one = hn::Set(di, 1);
        const VI izero = hn::Zero(di);
        const VI depth_stride_v = hn::Set(di, int32_t(prev_depth_stride));
        const VI id_stride_v = hn::Set(di, int32_t(prev_id_stride));
        const auto* prev_id_i = reinterpret_cast<const int32_t*>(prev_id);
        // floor() by truncation and correction, as the scalar code.
        auto floor_split = [&](VF v, VI& i, VF& f) {
            i = hn::ConvertTo(di, v);
            i = i - hn::IfThenElseZero(hn::RebindMask(di, v < hn::ConvertTo(df, i)), one);
            f = v - hn::ConvertTo(df, i);
        };
        alignas(64) int32_t X0[HWY_MAX_BYTES / 4], X1[HWY_MAX_BYTES / 4];
        alignas(64) int32_t Y0[HWY_MAX_BYTES / 4], Y1[HWY_MAX_BYTES / 4];
        alignas(64) float FX[HWY_MAX_BYTES / 4], FY[HWY_MAX_BYTES / 4];
        alignas(64) int32_t DEPTH_OK[HWY_MAX_BYTES / 4], IDS_OK[HWY_MAX_BYTES / 4];
        for (; x + lanes <= width; x += lanes) {
            const VF xf = lane_numbers + hn::Set(df, float(x));
            const VF z = hn::LoadU(df, zr + x);
            VF mx, my;
            hn::LoadInterleaved2(df, &mr[x].x, mx, my);
            const VF w = v_wz * z + v_w1;
            const VF lin = v_kx * (xf + v_px0) + v_row;
            const VF z_expected = w * lin + (v_kz * z + v_k1);
            const VF qx = (xf + v_qx0) + mx, qy = v_qy + my;
            const auto motion_ok = hn::And((mx - mx) == zero, (my - my) == zero);
            const auto surface = hn::And(
                hn::And((z - z) == zero, (z_expected - z_expected) == zero), z_expected > zero);
            const auto background = background_hits ? (z == inf) : hn::FirstN(df, 0);
            const auto inside =
                hn::And(hn::And(qx >= zero, qy >= zero), hn::And(qx <= v_fpw, qy <= v_fph));
            const auto go = hn::And(hn::And(motion_ok, inside), hn::Or(surface, background));
            if (!hn::AllTrue(df, go)) {
                for (int i = 0; i < lanes; ++i) record(x + i, classify(x + i), hrow);
                continue;
            }
            VI ix, iy;
            VF fx, fy;
            floor_split(qx - half, ix, fx);
            floor_split(qy - half, iy, fy);
            const VI x0 = hn::Min(hn::Max(ix, izero), v_pw1),
                     y0 = hn::Min(hn::Max(iy, izero), v_ph1);
            const VI x1 =
                hn::IfThenElse(hn::RebindMask(di, fx == zero), x0, hn::Min(ix + one, v_pw1));
            const VI y1 =
                hn::IfThenElse(hn::RebindMask(di, fy == zero), y0, hn::Min(iy + one, v_ph1));
            const VI r0 = y0 * depth_stride_v, r1 = y1 * depth_stride_v;
            const VF a = hn::GatherIndex(df, prev_depth, r0 + x0);
            const VF b = hn::GatherIndex(df, prev_depth, r0 + x1);
            const VF c = hn::GatherIndex(df, prev_depth, r1 + x0);
            const VF d = hn::GatherIndex(df, prev_depth, r1 + x1);
            auto ids_agree = hn::FirstN(df, size_t(lanes));
            if (use_ids) {
                const VI me = hn::LoadU(di, reinterpret_cast<const int32_t*>(ir) + x);
                const VI i0 = y0 * id_stride_v, i1 = y1 * id_stride_v;
                const auto same = hn::And(hn::And(hn::GatherIndex(di, prev_id_i, i0 + x0) == me,
                                                  hn::GatherIndex(di, prev_id_i, i0 + x1) == me),
                                          hn::And(hn::GatherIndex(di, prev_id_i, i1 + x0) == me,
                                                  hn::GatherIndex(di, prev_id_i, i1 + x1) == me));
                ids_agree = hn::RebindMask(df, same);
            }
            const auto taps_finite = (((a - a) + (b - b)) + (c - c)) + (d - d) == zero;
            const VF top = a + (b - a) * fx, bottom = c + (d - c) * fx;
            const VF z_previous = top + (bottom - top) * fy;
            const VF tolerance = use_ids ? hn::IfThenElse(ids_agree, v_id_tol, v_tol) : v_tol;
            const auto close = hn::Abs(z_expected - z_previous) <= tolerance * z_expected;
            const auto all_background =
                hn::And(hn::And(a == inf, b == inf), hn::And(c == inf, d == inf));
            const auto depth_ok = hn::Or(hn::And(background, all_background),
                                         hn::AndNot(background, hn::And(taps_finite, close)));
            hn::Store(x0, di, X0), hn::Store(x1, di, X1), hn::Store(y0, di, Y0),
                hn::Store(y1, di, Y1);
            hn::Store(fx, df, FX), hn::Store(fy, df, FY);
            hn::Store(hn::VecFromMask(di, hn::RebindMask(di, depth_ok)), di, DEPTH_OK);
            hn::Store(hn::VecFromMask(di, hn::RebindMask(di, ids_agree)), di, IDS_OK);
            for (int i = 0; i < lanes; ++i) {
                Outcome o = Hit;
                if (!DEPTH_OK[i]) {
                    o = Occluded;
                } else if (!IDS_OK[i]) {
                    o = OtherId;
                } else {
                    const float* p0 = in + Y0[i] * in_stride;
                    const float* p1 = in + Y1[i] * in_stride;
                    const std::ptrdiff_t c0 = std::ptrdiff_t(X0[i]) * n,
                                         c1 = std::ptrdiff_t(X1[i]) * n;
                    if (!fetch<C>(p0 + c0, p0 + c1, p1 + c0, p1 + c1, n, FX[i], FY[i],
                                  orow + std::ptrdiff_t(x + i) * n))
                        o = Invalid;
                }
                record(x + i, o, hrow);
            }
        }
#endif
        for (; x < width; ++x) record(x, classify(x), hrow);
    }
    counts[Hit] += hits;
}

void ReprojectRows(const Kernel& kernel, int y_begin, int y_end, int step, std::size_t* counts) {
    switch (kernel.channels) {
        case 1:
            return reproject_rows<1>(kernel, y_begin, y_end, step, counts);
        case 2:
            return reproject_rows<2>(kernel, y_begin, y_end, step, counts);
        case 3:
            return reproject_rows<3>(kernel, y_begin, y_end, step, counts);
        case 4:
            return reproject_rows<4>(kernel, y_begin, y_end, step, counts);
        default:
            return reproject_rows<0>(kernel, y_begin, y_end, step, counts);
    }
}

}  // namespace reprise::warp::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace reprise::warp {

HWY_EXPORT(ReprojectRows);

ReprojectCounts reproject(const GBufferView& current, const GBufferView& previous,
                          ConstPayload previous_payload, Payload out, ImageView<uint8_t> hit,
                          const ReprojectOptions& options) {
    check_contract(current, previous, previous_payload, out, hit);
    const Setup s = make_setup(current, previous, options);
    const Kernel k{s,
                   current.depth.width,
                   previous.depth.width,
                   previous.depth.height,
                   previous_payload.channels,
                   current.depth.data,
                   current.depth.stride,
                   current.motion.data,
                   current.motion.stride,
                   current.id.data,
                   current.id.stride,
                   previous.depth.data,
                   previous.depth.stride,
                   previous.id.data,
                   previous.id.stride,
                   previous_payload.data,
                   previous_payload.stride,
                   out.data,
                   out.stride,
                   hit.empty() ? nullptr : hit.data,
                   hit.stride};
    std::atomic<std::size_t> total[OutcomeCount] = {};
    const int step = std::max(1, options.step);
    const int height = current.depth.height, sampled_rows = (height + step - 1) / step;
    const int grain = std::max(1, 4096 * step / std::max(1, k.width));
    parallel_for(
        0, sampled_rows,
        [&](int r0, int r1) {
            std::size_t n[OutcomeCount] = {};
            HWY_DYNAMIC_DISPATCH(ReprojectRows)(k, r0 * step, std::min(r1 * step, height), step, n);
            for (int i = 0; i < OutcomeCount; ++i)
                total[i].fetch_add(n[i], std::memory_order_relaxed);
        },
        grain);
    std::size_t n[OutcomeCount];
    for (int i = 0; i < OutcomeCount; ++i) n[i] = total[i].load();
    return to_counts(n);
}

ReprojectCounts reproject_reference(const GBufferView& current, const GBufferView& previous,
                                    ConstPayload previous_payload, Payload out,
                                    ImageView<uint8_t> hit, const ReprojectOptions& options) {
    check_contract(current, previous, previous_payload, out, hit);
    const Setup s = make_setup(current, previous, options);
    const int w = current.depth.width, h = current.depth.height;
    const int pw = previous.depth.width, ph = previous.depth.height;
    const int channels = previous_payload.channels;
    std::size_t n[OutcomeCount] = {};
    const int step = std::max(1, options.step);
    for (int y = 0; y < h; y += step) {
        for (int x = 0; x < w; x += step) {
            auto outcome = [&]() -> Outcome {
                const float z = current.depth(x, y);
                const glm::vec2 m = current.motion(x, y);
                if (!std::isfinite(m.x) || !std::isfinite(m.y)) return Invalid;
                const bool background = s.background && z == kInf;
                if (!std::isfinite(z) && !background) return Invalid;
                float z_expected = 0.0f;
                if (!background) {
                    z_expected =
                        expected_depth(s, float(x) + s.px0, s.ky * (float(y) + s.py0) + s.kw, z);
                    if (!std::isfinite(z_expected)) return Invalid;
                    if (z_expected <= 0.0f) return Behind;
                }
                Bilinear b =
                    bilinear_taps((float(x) + s.qx0) + m.x, (float(y) + s.qy0) + m.y, pw, ph);
                if (!b.inside) return Offscreen;
                if (b.fx == 0.0f) b.x1 = b.x0;
                if (b.fy == 0.0f) b.y1 = b.y0;
                const int xs[4] = {b.x0, b.x1, b.x0, b.x1}, ys[4] = {b.y0, b.y0, b.y1, b.y1};

                bool ids_agree = true;
                if (s.use_ids)
                    for (int i = 0; i < 4; ++i)
                        ids_agree &= previous.id(xs[i], ys[i]) == current.id(x, y);
                bool all_finite = true, all_background = true;
                for (int i = 0; i < 4; ++i) {
                    const float d = previous.depth(xs[i], ys[i]);
                    all_finite &= std::isfinite(d);
                    all_background &= d == kInf;
                }
                if (background) {
                    if (!all_background) return Occluded;
                } else {
                    if (!all_finite) return Occluded;
                    const float z_previous = bilinear_fetch(previous.depth, b);
                    const float tolerance = s.use_ids && ids_agree ? s.id_tolerance : s.tolerance;
                    if (!(std::abs(z_expected - z_previous) <= tolerance * z_expected))
                        return Occluded;
                }
                if (!ids_agree) return OtherId;

                auto value = [&](int c) {
                    const float* p[4];
                    for (int i = 0; i < 4; ++i) p[i] = previous_payload.pixel(xs[i], ys[i]);
                    const float top = p[0][c] + (p[1][c] - p[0][c]) * b.fx;
                    const float bottom = p[2][c] + (p[3][c] - p[2][c]) * b.fx;
                    return top + (bottom - top) * b.fy;
                };
                for (int c = 0; c < channels; ++c)
                    if (!std::isfinite(value(c))) return Invalid;
                for (int c = 0; c < channels; ++c) out.pixel(x, y)[c] = value(c);
                return Hit;
            };
            const Outcome o = outcome();
            ++n[o];
            if (!hit.empty()) hit(x, y) = o == Hit;
        }
    }
    return to_counts(n);
}

}  // namespace reprise::warp
#endif  // HWY_ONCE
