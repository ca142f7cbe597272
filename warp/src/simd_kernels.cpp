// The SIMD versions of kernels.hpp, compiled once per Highway target and chosen at run time.
// Each spells out its scalar reference's operations in the same order (no FMA: this file is
// compiled with -ffp-contract=off), so it gives the same bits; the last width % lanes pixels of a
// row go through the reference itself.
#include <cmath>
#include <limits>

#include "kernels.hpp"
#include "reprise/warp/fill.hpp"
#include "reprise/warp/sample.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "simd_kernels.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "bicubic-inl.h"

HWY_BEFORE_NAMESPACE();
namespace reprise::warp::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

std::size_t BlendRowSimd(const BlendRow& r) {
    const hn::ScalableTag<float> df;
    const hn::RebindToSigned<decltype(df)> di;
    const hn::Rebind<uint8_t, decltype(df)> du8;
    using VF = hn::Vec<decltype(df)>;
    const int n = int(hn::Lanes(df));
    const VF one_minus_s = hn::Set(df, 1.0f - r.s), s = hn::Set(df, r.s);
    const VF scale = hn::Set(df, r.motion_scale), tolerance = hn::Set(df, kSameSurface);
    const VF inf = hn::Set(df, std::numeric_limits<float>::infinity());
    const auto zero_i = hn::Zero(di), one_i = hn::Set(di, 1);
    const auto stretched = hn::Set(di, int32_t{kCoveredStretched});
    std::size_t holes = 0;
    int x = 0;
    for (; x + n <= r.width; x += n) {
        const auto qa = hn::PromoteTo(di, hn::LoadU(du8, r.covered_a + x));
        const auto qb = hn::PromoteTo(di, hn::LoadU(du8, r.covered_b + x));
        const auto ca = hn::RebindMask(df, qa != zero_i), cb = hn::RebindMask(df, qb != zero_i);
        const auto covered = hn::Or(ca, cb);
        hn::StoreU(hn::DemoteTo(du8, hn::IfThenElseZero(hn::RebindMask(di, covered), one_i)), du8,
                   r.valid + x);
        holes += std::size_t(n) - hn::CountTrue(df, covered);
        const auto sa = hn::RebindMask(df, qa == stretched),
                   sb = hn::RebindMask(df, qb == stretched);
        const auto one_stretched = hn::And(hn::And(ca, cb), hn::Xor(sa, sb));

        const VF za = hn::LoadU(df, r.depth_a + x), zb = hn::LoadU(df, r.depth + x);
        const auto both = hn::And(ca, cb);
        const VF nearer = hn::IfThenElse(zb < za, zb, za);  // std::min(za, zb), signed zeros too
        const auto unstretched = hn::AndNot(one_stretched, both);
        const auto same = hn::And(unstretched, hn::Abs(za - zb) <= tolerance * nearer);
        const auto background =
            hn::And(unstretched, hn::And(hn::Abs(za) == inf, hn::Abs(zb) == inf));
        const auto blend = hn::Or(same, background);
        const auto take_a = hn::Or(
            hn::And(one_stretched, sb),
            hn::AndNot(one_stretched,
                       hn::AndNot(blend, hn::And(ca, hn::Or(hn::Not(cb), hn::Not(zb < za))))));

        float* color = &r.color[x].x;
        const float* color_a = &r.color_a[x].x;
        VF ar, ag, ab, aa, br, bg, bb, ba;
        hn::LoadInterleaved4(df, color_a, ar, ag, ab, aa);
        hn::LoadInterleaved4(df, color, br, bg, bb, ba);
        auto merge = [&](VF a, VF b) {
            return hn::IfThenElse(blend, one_minus_s * a + s * b, hn::IfThenElse(take_a, a, b));
        };
        hn::StoreInterleaved4(merge(ar, br), merge(ag, bg), merge(ab, bb), merge(aa, ba), df,
                              color);
        const VF depth = hn::IfThenElse(
            same, nearer, hn::IfThenElse(background, inf, hn::IfThenElse(take_a, za, zb)));
        hn::StoreU(depth, df, r.depth + x);

        VF max, may, mbx, mby;
        hn::LoadInterleaved2(df, &r.motion_a[x].x, max, may);
        hn::LoadInterleaved2(df, &r.motion[x].x, mbx, mby);
        hn::StoreInterleaved2(hn::IfThenElse(take_a, max, mbx) * scale,
                              hn::IfThenElse(take_a, may, mby) * scale, df, &r.motion[x].x);
    }
    if (x < r.width) {
        BlendRow tail = r;
        tail.covered_a += x, tail.covered_b += x, tail.depth_a += x, tail.color_a += x;
        tail.motion_a += x, tail.depth += x, tail.color += x, tail.motion += x, tail.valid += x;
        tail.width = r.width - x;
        holes += blend_row_reference(tail);
    }
    return holes;
}

std::size_t StaticLayerRowSimd(const StaticLayerTest& t, int y, int width, const float* depth,
                               const glm::vec2* motion, float* depth_out, glm::vec2* motion_out) {
    const hn::ScalableTag<float> df;
    using VF = hn::Vec<decltype(df)>;
    const int n = int(hn::Lanes(df));
    const glm::mat4& P = t.projection;
    const glm::mat4& A = t.to_previous;
    const glm::mat4& B = t.to_future;
    auto splat = [&](float v) { return hn::Set(df, v); };
    const VF half = splat(0.5f), one = splat(1.0f), two = splat(2.0f), zero = hn::Zero(df);
    const VF inf = splat(std::numeric_limits<float>::infinity());
    const VF nan = splat(std::numeric_limits<float>::quiet_NaN());
    const VF fw = splat(t.width), fh = splat(t.height), tolerance2 = splat(t.tolerance2);
    const VF background_zv = splat(t.background_zv), background_w = splat(t.background_w);
    const float py_scalar = float(y) + 0.5f;
    const VF py = splat(py_scalar), ny = splat(1.0f - 2.0f * py_scalar / t.height);
    const VF lanes = hn::Iota(df, 0.0f);
    // Row r of M times (vx, vy, zv, w), summed as transform_row does.
    auto row = [&](const glm::mat4& M, int r, VF vx, VF vy, VF zv, VF w) {
        return (splat(M[0][r]) * vx + splat(M[1][r]) * vy) +
               (splat(M[2][r]) * zv + splat(M[3][r]) * w);
    };
    std::size_t dynamic = 0;
    int x = 0;
    for (; x + n <= width; x += n) {
        const VF z = hn::LoadU(df, depth + x);
        VF mx, my;
        hn::LoadInterleaved2(df, &motion[x].x, mx, my);
        const VF px = (splat(float(x)) + lanes) + half;
        const VF nx = two * px / fw - one;
        const auto background = z == inf;
        const VF zv = hn::IfThenElse(background, background_zv, hn::Neg(z));
        const VF w = hn::IfThenElse(background, background_w, one);
        const VF wc = splat(P[2][3]) * zv + splat(P[3][3]) * w;
        const VF vx = (nx * wc - splat(P[2][0]) * zv - splat(P[3][0]) * w) / splat(P[0][0]);
        const VF vy = (ny * wc - splat(P[2][1]) * zv - splat(P[3][1]) * w) / splat(P[1][1]);
        const VF aw = row(A, 3, vx, vy, zv, w), bw = row(B, 3, vx, vy, zv, w);
        const VF bx = (row(A, 0, vx, vy, zv, w) / aw * half + half) * fw;
        const VF by = (half - half * row(A, 1, vx, vy, zv, w) / aw) * fh;
        const VF lx = (row(B, 0, vx, vy, zv, w) / bw * half + half) * fw;
        const VF ly = (half - half * row(B, 1, vx, vy, zv, w) / bw) * fh;
        const VF ex = bx - px - mx, ey = by - py - my;
        const auto still = hn::And(
            hn::And(hn::And(z == z, (mx - mx) == zero), hn::And((my - my) == zero, aw > zero)),
            hn::And(bw > zero, ex * ex + ey * ey <= tolerance2));
        hn::StoreU(hn::IfThenElse(still, z, nan), df, depth_out + x);
        hn::StoreInterleaved2(hn::IfThenElse(still, lx - px, nan),
                              hn::IfThenElse(still, ly - py, nan), df, &motion_out[x].x);
        dynamic += std::size_t(n) - hn::CountTrue(df, still);
    }
    if (x < width)
        dynamic += static_layer_row_reference(t, y, x, width, depth, motion, depth_out, motion_out);
    return dynamic;
}

PullCounts PullRowSimd(const PullRow& r) {
    const int coarse = (r.fine_width + 1) / 2;
#if HWY_TARGET == HWY_SCALAR
    return pull_row_reference(r, 0, coarse);
#else
    if (r.rows != 2) return pull_row_reference(r, 0, coarse);
    const hn::ScalableTag<float> df;
    const hn::RebindToUnsigned<decltype(df)> du32;
    const hn::Rebind<uint16_t, decltype(df)> du16;
    const hn::Rebind<uint8_t, decltype(df)> du8;
    using VF = hn::Vec<decltype(df)>;
    const int n = int(hn::Lanes(df));
    const VF zero = hn::Zero(df), one = hn::Set(df, 1.0f), four = hn::Set(df, 4.0f);
    const VF inf = hn::Set(df, std::numeric_limits<float>::infinity());
    const VF ratio = hn::Set(df, kBackgroundDepthRatio);
    const auto low_byte = hn::Set(du32, 0x00FFu), high_byte = hn::Set(du32, 0xFF00u);
    const auto zero_u = hn::Zero(du32);
    // Both children of each pair valid (a pair of bytes read as one 16-bit lane).
    auto pair_valid = [&](const uint8_t* m) {
        const auto v = hn::PromoteTo(du32, hn::LoadU(du16, reinterpret_cast<const uint16_t*>(m)));
        return hn::RebindMask(df, hn::And((v & low_byte) != zero_u, (v & high_byte) != zero_u));
    };
    auto sane = [&](VF d) {  // sane_depth: NaN -> +inf, below 0 -> 0
        return hn::IfThenElse(d != d, inf, hn::IfThenElse(d < zero, zero, d));
    };
    auto larger = [](VF a, VF b) { return hn::IfThenElse(a < b, b, a); };  // std::max(a, b)
    PullCounts counts;
    const int pairs = r.fine_width / 2;
    int i = 0;
    for (; i + n <= pairs; i += n) {
        const int x0 = 2 * i;
        VF sum[3];
        {
            VF c0[4], c1[4], c2[4], c3[4];  // row 0 pixels x0.., x0 + n..; row 1 the same
            hn::LoadInterleaved4(df, &r.row0[x0].x, c0[0], c0[1], c0[2], c0[3]);
            hn::LoadInterleaved4(df, &r.row0[x0 + n].x, c1[0], c1[1], c1[2], c1[3]);
            hn::LoadInterleaved4(df, &r.row1[x0].x, c2[0], c2[1], c2[2], c2[3]);
            hn::LoadInterleaved4(df, &r.row1[x0 + n].x, c3[0], c3[1], c3[2], c3[3]);
            for (int c = 0; c < 3; ++c)  // (((0 + a) + b) + e) + g, children in raster order
                sum[c] = zero + hn::ConcatEven(df, c1[c], c0[c]) + hn::ConcatOdd(df, c1[c], c0[c]) +
                         hn::ConcatEven(df, c3[c], c2[c]) + hn::ConcatOdd(df, c3[c], c2[c]);
        }
        auto fast = hn::And(hn::And(pair_valid(r.valid0 + x0), pair_valid(r.valid1 + x0)),
                            hn::And(hn::And((sum[0] - sum[0]) == zero, (sum[1] - sum[1]) == zero),
                                    (sum[2] - sum[2]) == zero));
        VF dmax = zero;
        if (r.depth0) {
            VF a, b, e, g;
            hn::LoadInterleaved2(df, r.depth0 + x0, a, b);
            hn::LoadInterleaved2(df, r.depth1 + x0, e, g);
            a = sane(a), b = sane(b), e = sane(e), g = sane(g);
            dmax = larger(larger(a, b), larger(e, g));
            fast = hn::And(fast, hn::And(hn::And(a * ratio >= dmax, b * ratio >= dmax),
                                         hn::And(e * ratio >= dmax, g * ratio >= dmax)));
        }
        if (!hn::AllTrue(df, fast)) {  // a hole or a depth edge among them: the general code
            const PullCounts c = pull_row_reference(r, i, i + n);
            counts.holes += c.holes, counts.empty += c.empty;
            continue;
        }
        if (r.depth0) hn::StoreU(dmax, df, r.out_depth + i);
        hn::StoreInterleaved4(sum[0] / four, sum[1] / four, sum[2] / four, one, df, &r.out[i].x);
        hn::StoreU(hn::Zero(du8), du8, r.hole_bits + i);
    }
    const PullCounts tail = pull_row_reference(r, i, coarse);
    counts.holes += tail.holes, counts.empty += tail.empty;
    return counts;
#endif
}

std::size_t PullLevelRowSimd(const PullLevelRow& r) {
    const int coarse = (r.fine_width + 1) / 2;
#if HWY_TARGET == HWY_SCALAR
    return pull_level_row_reference(r, 0, coarse);
#else
    if (r.rows != 2) return pull_level_row_reference(r, 0, coarse);
    const hn::ScalableTag<float> df;
    using VF = hn::Vec<decltype(df)>;
    const int n = int(hn::Lanes(df));
    const VF zero = hn::Zero(df), one = hn::Set(df, 1.0f), four = hn::Set(df, 4.0f);
    const VF ratio = hn::Set(df, kBackgroundDepthRatio);
    auto larger = [](VF a, VF b) { return hn::IfThenElse(a < b, b, a); };  // std::max(a, b)
    std::size_t empty = 0;
    const int pairs = r.fine_width / 2;
    int i = 0;
    for (; i + n <= pairs; i += n) {
        const int x0 = 2 * i;
        VF c0[4], c1[4], c2[4], c3[4];
        hn::LoadInterleaved4(df, &r.row0[x0].x, c0[0], c0[1], c0[2], c0[3]);
        hn::LoadInterleaved4(df, &r.row0[x0 + n].x, c1[0], c1[1], c1[2], c1[3]);
        hn::LoadInterleaved4(df, &r.row1[x0].x, c2[0], c2[1], c2[2], c2[3]);
        hn::LoadInterleaved4(df, &r.row1[x0 + n].x, c3[0], c3[1], c3[2], c3[3]);
        VF even[4][2],
            odd[4][2];  // [channel][row]: children (0,0) (0,1) in even, (1,0) (1,1) in odd
        VF sum[3];
        for (int c = 0; c < 4; ++c) {
            even[c][0] = hn::ConcatEven(df, c1[c], c0[c]),
            odd[c][0] = hn::ConcatOdd(df, c1[c], c0[c]);
            even[c][1] = hn::ConcatEven(df, c3[c], c2[c]),
            odd[c][1] = hn::ConcatOdd(df, c3[c], c2[c]);
            if (c < 3) sum[c] = zero + even[c][0] + odd[c][0] + even[c][1] + odd[c][1];
        }
        auto fast = hn::And(hn::And(even[3][0] == one, odd[3][0] == one),
                            hn::And(even[3][1] == one, odd[3][1] == one));
        VF dmax = zero;
        if (r.depth0) {
            VF a, b, e, g;
            hn::LoadInterleaved2(df, r.depth0 + x0, a, b);
            hn::LoadInterleaved2(df, r.depth1 + x0, e, g);
            dmax = larger(larger(a, b), larger(e, g));
            fast = hn::And(fast, hn::And(hn::And(a * ratio >= dmax, b * ratio >= dmax),
                                         hn::And(e * ratio >= dmax, g * ratio >= dmax)));
        }
        if (!hn::AllTrue(df, fast)) {
            empty += pull_level_row_reference(r, i, i + n);
            continue;
        }
        if (r.depth0) hn::StoreU(dmax, df, r.out_depth + i);
        hn::StoreInterleaved4(sum[0] / four, sum[1] / four, sum[2] / four, one, df, &r.out[i].x);
    }
    return empty + pull_level_row_reference(r, i, coarse);
#endif
}

void DisplacementRowSimd(const DisplacementTest& t, int y, int width, const float* depth,
                         glm::vec2* displacement, float* target_depth) {
    const hn::ScalableTag<float> df;
    using VF = hn::Vec<decltype(df)>;
    const int n = int(hn::Lanes(df));
    const glm::mat4& P = t.projection;
    const glm::mat4& M = t.to_clip;
    const glm::mat4& V = t.to_view;
    auto splat = [&](float v) { return hn::Set(df, v); };
    const VF half = splat(0.5f), one = splat(1.0f), two = splat(2.0f), zero = hn::Zero(df);
    const VF inf = splat(std::numeric_limits<float>::infinity());
    const VF nan = splat(std::numeric_limits<float>::quiet_NaN());
    const VF fw = splat(t.width), fh = splat(t.height);
    const VF background_zv = splat(t.background_zv), background_w = splat(t.background_w);
    const float py_scalar = float(y) + 0.5f;
    const VF py = splat(py_scalar), ny = splat(1.0f - 2.0f * py_scalar / t.height);
    const VF lanes = hn::Iota(df, 0.0f);
    // Row r of A times (vx, vy, zv, w), summed as transform_row does.
    auto row = [&](const glm::mat4& A, int r, VF vx, VF vy, VF zv, VF w) {
        return (splat(A[0][r]) * vx + splat(A[1][r]) * vy) +
               (splat(A[2][r]) * zv + splat(A[3][r]) * w);
    };
    int x = 0;
    for (; x + n <= width; x += n) {
        const VF z = hn::LoadU(df, depth + x);
        const VF px = (splat(float(x)) + lanes) + half;
        const VF nx = two * px / fw - one;
        const auto background = z == inf;
        const VF zv = hn::IfThenElse(background, background_zv, hn::Neg(z));
        const VF w = hn::IfThenElse(background, background_w, one);
        const VF wc = splat(P[2][3]) * zv + splat(P[3][3]) * w;
        const VF vx = (nx * wc - splat(P[2][0]) * zv - splat(P[3][0]) * w) / splat(P[0][0]);
        const VF vy = (ny * wc - splat(P[2][1]) * zv - splat(P[3][1]) * w) / splat(P[1][1]);
        const VF cw = row(M, 3, vx, vy, zv, w);
        const VF lx = (row(M, 0, vx, vy, zv, w) / cw * half + half) * fw;
        const VF ly = (half - half * row(M, 1, vx, vy, zv, w) / cw) * fh;
        const VF tz = hn::Neg(row(V, 2, vx, vy, zv, w));
        const auto ok =
            hn::And(hn::And(z >= zero, cw > zero), hn::And((lx - lx) == zero, (ly - ly) == zero));
        hn::StoreInterleaved2(hn::IfThenElse(ok, lx - px, nan), hn::IfThenElse(ok, ly - py, nan),
                              df, &displacement[x].x);
        hn::StoreU(hn::IfThenElse(ok, hn::IfThenElse(background, inf, tz), nan), df,
                   target_depth + x);
    }
    if (x < width) displacement_row_reference(t, y, x, width, depth, displacement, target_depth);
}

// Positions in vector lanes, then bicubic-inl.h's lookups. Pixels whose bicubic taps reach past
// the border go to the reference one by one.
void RefetchRowSimd(const RefetchRow& r) {
#if HWY_TARGET == HWY_SCALAR
    refetch_row_reference(r, 0, r.width);
#else
    const hn::ScalableTag<float> df;
    const hn::RebindToSigned<decltype(df)> di;
    const hn::Rebind<uint8_t, decltype(df)> du8;
    const hn::Full128<float> d4;
    using VF = hn::Vec<decltype(df)>;
    using VI = hn::Vec<decltype(di)>;
    const int n = int(hn::Lanes(df));
    const int sw = r.color.width, sh = r.color.height;
    auto splat = [&](float v) { return hn::Set(df, v); };
    const VF zero = hn::Zero(df), half = splat(0.5f);
    const VF lane_numbers = hn::Iota(df, 0.0f);  // Iota(df, x) in the loop stalls (Highway 1.0)
    const VF fsw = splat(float(sw)), fsh = splat(float(sh)), factor = splat(r.factor);
    const VF qy = splat(float(r.y) + 0.5f);
    const VI zero_i = hn::Zero(di), one_i = hn::Set(di, 1);
    const VI last_x = hn::Set(di, sw - 1), last_y = hn::Set(di, sh - 1);
    const VI motion_stride = hn::Set(di, int(r.motion.stride));
    const float* motion = &r.motion.data->x;
    auto floor_small = [&](VF v) {  // as warp::floor_small
        const VI i = hn::ConvertTo(di, v);
        return hn::IfThenElse(hn::RebindMask(di, v < hn::ConvertTo(df, i)), i - one_i, i);
    };
    BicubicLanes lanes;
    int x = 0;
    for (; x + n <= r.width; x += n) {
        const auto covered =
            hn::RebindMask(df, hn::PromoteTo(di, hn::LoadU(du8, r.covered + x)) != zero_i);
        if (hn::AllFalse(df, covered)) continue;
        VF mx, my;
        hn::LoadInterleaved2(df, &r.target_motion[x].x, mx, my);
        const VF qx = (lane_numbers + splat(float(x))) + half;
        VF px = qx - factor * mx, py = qy - factor * my;
        auto go = hn::And(covered,
                          hn::And(hn::And(px >= zero, py >= zero), hn::And(px <= fsw, py <= fsh)));
        if (hn::AllFalse(df, go)) continue;
        // The source motion, bilinear at p (bilinear_taps + bilinear_fetch).
        px = hn::IfThenElseZero(go, px), py = hn::IfThenElseZero(go, py);
        const VF sx = px - half, sy = py - half;
        const VI ix = floor_small(sx), iy = floor_small(sy);
        const VF fx = sx - hn::ConvertTo(df, ix), fy = sy - hn::ConvertTo(df, iy);
        const VI x0 = hn::Min(hn::Max(ix, zero_i), last_x);
        const VI x1 = hn::Min(hn::Max(ix + one_i, zero_i), last_x);
        const VI r0 = hn::Min(hn::Max(iy, zero_i), last_y) * motion_stride;
        const VI r1 = hn::Min(hn::Max(iy + one_i, zero_i), last_y) * motion_stride;
        const VI i00 = hn::ShiftLeft<1>(r0 + x0), i01 = hn::ShiftLeft<1>(r0 + x1);
        const VI i10 = hn::ShiftLeft<1>(r1 + x0), i11 = hn::ShiftLeft<1>(r1 + x1);
        auto lerp2 = [&](const float* base) {
            const VF a = hn::GatherIndex(df, base, i00), b = hn::GatherIndex(df, base, i01);
            const VF c = hn::GatherIndex(df, base, i10), d = hn::GatherIndex(df, base, i11);
            const VF top = a + (b - a) * fx, bottom = c + (d - c) * fx;
            return top + (bottom - top) * fy;
        };
        const VF smx = lerp2(motion), smy = lerp2(motion + 1);
        go = hn::And(go, hn::And((smx - smx) == zero, (smy - smy) == zero));
        px = qx - factor * smx, py = qy - factor * smy;
        go = hn::And(go, hn::And(hn::And(px >= zero, py >= zero), hn::And(px <= fsw, py <= fsh)));
        if (hn::AllFalse(df, go)) continue;
        const auto inner = BicubicPrepare(df, hn::IfThenElseZero(go, px),
                                          hn::IfThenElseZero(go, py), sw, sh, lanes);
        alignas(64) uint8_t bits[kBicubicMaxLanes / 8 + 8];
        hn::StoreMaskBits(df, go, bits);
        alignas(64) uint8_t inner_bits[kBicubicMaxLanes / 8 + 8];
        hn::StoreMaskBits(df, inner, inner_bits);
        for (int i = 0; i < n; ++i) {
            if (!((bits[i / 8] >> (i % 8)) & 1)) continue;
            if (!((inner_bits[i / 8] >> (i % 8)) & 1)) {
                refetch_row_reference(r, x + i, x + i + 1);
                continue;
            }
            glm::vec4 c;
            hn::StoreU(BicubicSum(r.color, lanes, i), d4, &c.x);
            if (std::isfinite(c.r + c.g + c.b + c.a)) r.out[x + i] = c;
        }
    }
    refetch_row_reference(r, x, r.width);
#endif
}

void BicubicRowSimd(const BicubicRow& r) {
#if HWY_TARGET == HWY_SCALAR
    bicubic_row_reference(r);
#else
    const hn::ScalableTag<float> df;
    const hn::Full128<float> d4;
    const int n = int(hn::Lanes(df));
    BicubicLanes lanes;
    int i = 0;
    for (; i + n <= r.count; i += n) {
        hn::Vec<decltype(df)> x, y;
        hn::LoadInterleaved2(df, &r.positions[i].x, x, y);
        const auto inside = BicubicPrepare(df, x, y, r.color.width, r.color.height, lanes);
        alignas(64) uint8_t bits[kBicubicMaxLanes / 8 + 8];
        hn::StoreMaskBits(df, inside, bits);
        for (int k = 0; k < n; ++k) {
            if ((bits[k / 8] >> (k % 8)) & 1)
                hn::StoreU(BicubicSum(r.color, lanes, k), d4, &r.out[i + k].x);
            else
                r.out[i + k] = bicubic_fetch(r.color, r.positions[i + k].x, r.positions[i + k].y);
        }
    }
    bicubic_row_reference({r.color, r.positions + i, r.count - i, r.out + i});
#endif
}

// The rgb lanes of interleaved RGBA, for vectors of a multiple of four lanes.
template <class D>
auto ColourLanes(D d) {
    const hn::RebindToSigned<D> di;
    return hn::RebindMask(d, hn::And(hn::Iota(di, 0), hn::Set(di, 3)) != hn::Set(di, 3));
}

void PerceptualEncodeRowSimd(const glm::vec4* from, glm::vec4* to, int width) {
    const hn::ScalableTag<float> df;
    const int n = int(hn::Lanes(df));
    int x = 0;
    if (n % 4 == 0) {
        const auto rgb = ColourLanes(df);
        const float* in = &from[0].x;
        float* out = &to[0].x;
        for (; (x + n / 4) <= width; x += n / 4) {
            const auto v = hn::LoadU(df, in + 4 * x);
            const auto e = hn::CopySign(hn::Sqrt(hn::Abs(v)), v);
            hn::StoreU(hn::IfThenElse(rgb, e, v), df, out + 4 * x);
        }
    }
    perceptual_encode_row_reference(from + x, to + x, width - x);
}

void PerceptualDecodeRowSimd(glm::vec4* color, int width) {
    const hn::ScalableTag<float> df;
    const int n = int(hn::Lanes(df));
    int x = 0;
    if (n % 4 == 0) {
        const auto rgb = ColourLanes(df);
        float* c = &color[0].x;
        for (; (x + n / 4) <= width; x += n / 4) {
            const auto v = hn::LoadU(df, c + 4 * x);
            hn::StoreU(hn::IfThenElse(rgb, hn::Mul(v, hn::Abs(v)), v), df, c + 4 * x);
        }
    }
    perceptual_decode_row_reference(color + x, width - x);
}

}  // namespace reprise::warp::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace reprise::warp {

HWY_EXPORT(BlendRowSimd);
HWY_EXPORT(StaticLayerRowSimd);
HWY_EXPORT(PullRowSimd);
HWY_EXPORT(PullLevelRowSimd);
HWY_EXPORT(RefetchRowSimd);
HWY_EXPORT(DisplacementRowSimd);
HWY_EXPORT(BicubicRowSimd);
HWY_EXPORT(PerceptualEncodeRowSimd);
HWY_EXPORT(PerceptualDecodeRowSimd);

void perceptual_encode_row(const glm::vec4* from, glm::vec4* to, int width) {
    HWY_DYNAMIC_DISPATCH(PerceptualEncodeRowSimd)(from, to, width);
}

void perceptual_decode_row(glm::vec4* color, int width) {
    HWY_DYNAMIC_DISPATCH(PerceptualDecodeRowSimd)(color, width);
}

void bicubic_row(const BicubicRow& row) { HWY_DYNAMIC_DISPATCH(BicubicRowSimd)(row); }

void displacement_row(const DisplacementTest& test, int y, int width, const float* depth,
                      glm::vec2* displacement, float* target_depth) {
    HWY_DYNAMIC_DISPATCH(DisplacementRowSimd)(test, y, width, depth, displacement, target_depth);
}

void refetch_row(const RefetchRow& row) { HWY_DYNAMIC_DISPATCH(RefetchRowSimd)(row); }

std::size_t pull_level_row(const PullLevelRow& row) {
    return HWY_DYNAMIC_DISPATCH(PullLevelRowSimd)(row);
}

PullCounts pull_row(const PullRow& row) { return HWY_DYNAMIC_DISPATCH(PullRowSimd)(row); }

std::size_t blend_row(const BlendRow& row) { return HWY_DYNAMIC_DISPATCH(BlendRowSimd)(row); }

std::size_t static_layer_row(const StaticLayerTest& test, int y, int width, const float* depth,
                             const glm::vec2* motion, float* depth_out, glm::vec2* motion_out) {
    return HWY_DYNAMIC_DISPATCH(StaticLayerRowSimd)(test, y, width, depth, motion, depth_out,
                                                    motion_out);
}

}  // namespace reprise::warp
#endif
