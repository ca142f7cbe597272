// The forward splat's row kernels (splat_kernels.hpp), compiled once per Highway target and chosen
// at run time. Landing, validity and closeness are computed in lanes with the reference's
// operations in its order (no FMA: compiled with -ffp-contract=off). Where a run of lanes lands
// side by side in one target row (a camera pan, a rigid object, anything still), the z-test and
// the writes are done in lanes too; the lanes of any other vector go one by one through the
// reference's scalar z-test with their lane-computed landing.
#include <limits>

#include "splat_kernels.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "splat_kernels.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace reprise::warp::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

constexpr int kMaxLanes = HWY_MAX_BYTES / sizeof(float);

void SplatRowRangeSimd(const SplatScatter& s, int y, int& lo, int& hi) {
    const hn::ScalableTag<float> df;
    using VF = hn::Vec<decltype(df)>;
    const int n = int(hn::Lanes(df));
    const int sw = s.depth.width;
    const float* z_row = s.depth.row(y);
    const float* m_row = &s.motion.row(y)->x;
    const VF inf = hn::Set(df, std::numeric_limits<float>::infinity());
    const VF zero = hn::Zero(df), half = hn::Set(df, 0.5f), factor = hn::Set(df, s.factor);
    const VF row_centre = hn::Set(df, float(y) + 0.5f);
    const VF low = hn::Set(df, -1.5f), high = hn::Set(df, float(s.height) + 0.5f);
    VF dy_min = inf, dy_max = hn::Neg(inf);
    int x = 0;
    for (; x + n <= sw; x += n) {
        const VF z = hn::LoadU(df, z_row + x);
        VF mx, my;
        hn::LoadInterleaved2(df, m_row + 2 * x, mx, my);
        const VF dy = (row_centre + factor * my) - half;
        const auto ok = hn::And(hn::And(z >= zero, hn::And((mx - mx) == zero, (my - my) == zero)),
                                hn::And(dy > low, dy < high));
        dy_min = hn::Min(dy_min, hn::IfThenElse(ok, dy, inf));
        dy_max = hn::Max(dy_max, hn::IfThenElse(ok, dy, hn::Neg(inf)));
    }
    // Every folded value is finite and not NaN: the order of the fold does not matter (and floor
    // does not see the sign of a zero).
    float lowest = hn::GetLane(hn::MinOfLanes(df, dy_min)),
          highest = hn::GetLane(hn::MaxOfLanes(df, dy_max));
    splat_extent_reference(s, y, x, sw, lowest, highest);
    splat_rows_touched(s, lowest, highest, lo, hi);
}

void SplatRowSimd(const SplatScatter& s, int y, const Band& band) {
#if HWY_TARGET == HWY_SCALAR  // one lane: nothing to gain over the reference
    splat_row_reference(s, y, 0, s.depth.width, band);
#else
    const hn::ScalableTag<float> df;
    const hn::RebindToSigned<decltype(df)> di;
    const hn::Rebind<uint8_t, decltype(df)> du8;
    using VF = hn::Vec<decltype(df)>;
    using VI = hn::Vec<decltype(di)>;
    const int n = int(hn::Lanes(df));
    const int sw = s.depth.width;
    const WarpTarget& v = band.view;
    const int rows = v.color.height, band_last = band.y0 + rows - 1;
    const bool has_motion = !v.motion.empty();
    const float* z_row = s.depth.row(y);
    const float* m_row = &s.motion.row(y)->x;
    const float* c_row = &s.color.row(y)->x;

    constexpr float kSnap = 1e-3f;  // as in land()
    const VF zero = hn::Zero(df), half = hn::Set(df, 0.5f);
    const VF factor = hn::Set(df, s.factor), snap = hn::Set(df, kSnap);
    const VF row_centre = hn::Set(df, float(y) + 0.5f);
    const VF low = hn::Set(df, -1.5f), high_x = hn::Set(df, float(s.width) + 0.5f),
             high_y = hn::Set(df, float(s.height) + 0.5f);
    const VF scale = hn::Set(df, 127.0f), tol_lo = hn::Set(df, s.tol_lo),
             tol_hi = hn::Set(df, s.tol_hi);
    const VI one_i = hn::Set(di, 1), two_i = hn::Set(di, 2), max_i = hn::Set(di, 254),
             zero_i = hn::Zero(di);
    const VI lanes_i = hn::Iota(di, 0);
    const VF lanes = hn::Iota(df, 0.0f);
    const bool two = s.footprint == 2;
    // What the reference's land() adds before its floor: kSnap, or 0.5 for one-pixel footprints;
    // and the offset beyond which a landing covers a second column or row (never for one pixel).
    const VF bias = two ? snap : half;
    const VF spill = hn::Set(df, two ? kSnap : std::numeric_limits<float>::infinity());
    const auto all = zero == zero;

    auto floor_small = [&](VF t) {
        const VI i = hn::ConvertTo(di, t);  // truncates
        return hn::IfThenElse(hn::RebindMask(di, hn::ConvertTo(df, i) > t), i - one_i, i);
    };
    auto closeness = [&](VF ox, VF oy) {
        const VF d2 = ox * ox + oy * oy;
        return one_i + hn::Min(max_i, hn::ConvertTo(di, d2 * scale));
    };

    int x = 0;
    for (; x + n <= sw; x += n) {
        const VF z = hn::LoadU(df, z_row + x);
        VF mx, my;
        hn::LoadInterleaved2(df, m_row + 2 * x, mx, my);
        const VF dx = ((hn::Set(df, float(x)) + lanes + half) + factor * mx) - half;
        const VF dy = (row_centre + factor * my) - half;
        const auto ok =
            hn::And(hn::And(z >= zero, hn::And((mx - mx) == zero, (my - my) == zero)),
                    hn::And(hn::And(dx > low, dy > low), hn::And(dx < high_x, dy < high_y)));
        if (hn::AllFalse(df, ok)) continue;
        // Lanes that are not ok hold meaningless (but defined) integers from here on.
        const VI ix = floor_small(dx + bias), iy = floor_small(dy + bias);
        const VF ox = dx - hn::ConvertTo(df, ix), oy = dy - hn::ConvertTo(df, iy);
        const auto wide = ox > spill, tall = oy > spill;
        const VI iy_last = hn::IfThenElse(hn::RebindMask(di, tall), iy + one_i, iy);
        const auto touches =
            hn::And(hn::RebindMask(di, ok),
                    hn::And(hn::Set(di, band_last + 1) > iy, iy_last > hn::Set(di, band.y0 - 1)));
        if (hn::AllFalse(di, touches)) continue;
        // Every lane lands: in one target row, on consecutive columns, inside the target?
        const int ix0 = hn::GetLane(ix), iy0 = hn::GetLane(iy);
        if (!hn::AllTrue(df, ok) ||
            !hn::AllTrue(di, hn::And(iy == hn::Set(di, iy0), ix == hn::Set(di, ix0) + lanes_i)) ||
            ix0 < 0 || ix0 + n + 1 > s.width) {
            // Otherwise the lanes that reach the band, one by one in order.
            HWY_ALIGN int32_t xs[kMaxLanes], ys[kMaxLanes], nxs[kMaxLanes], nys[kMaxLanes];
            HWY_ALIGN int32_t reach[kMaxLanes];
            HWY_ALIGN float oxs[kMaxLanes], oys[kMaxLanes];
            hn::Store(ix, di, xs), hn::Store(iy, di, ys), hn::Store(ox, df, oxs);
            hn::Store(oy, df, oys), hn::Store(hn::IfThenElseZero(touches, one_i), di, reach);
            hn::Store(hn::IfThenElse(hn::RebindMask(di, wide), two_i, one_i), di, nxs);
            hn::Store(hn::IfThenElse(hn::RebindMask(di, tall), two_i, one_i), di, nys);
            for (int k = 0; k < n; ++k)
                if (reach[k])
                    splat_pixel(s, band, {xs[k], ys[k], nxs[k], nys[k], oxs[k], oys[k]},
                                z_row[x + k], s.motion.row(y)[x + k], s.color.row(y)[x + k]);
            continue;
        }
        VF cr, cg, cb, ca;
        hn::LoadInterleaved4(df, c_row + 4 * x, cr, cg, cb, ca);
        // One target pixel per lane and pass; of the two lanes that reach a pixel in one row
        // (i = 1 of lane k, i = 0 of lane k + 1), the earlier in source order goes first.
        for (int j = 0; j < (two ? 2 : 1); ++j) {
            const int row = iy0 + j - band.y0;
            if (row < 0 || row >= rows) continue;
            const VF oyj = oy - hn::Set(df, float(j));
            const auto in_row = j == 0 ? all : tall;
            uint8_t* q_row = v.covered.row(row);
            float* d_row = v.depth.row(row);
            float* col_row = &v.color.row(row)->x;
            for (int i = two ? 1 : 0; i >= 0; --i) {
                const auto active = i == 0 ? in_row : hn::And(in_row, wide);
                if (hn::AllFalse(df, active)) continue;
                const int tx = ix0 + i;
                const VI q = closeness(ox - hn::Set(df, float(i)), oyj);
                const VI stored_q = hn::PromoteTo(di, hn::LoadU(du8, q_row + tx));
                const VF stored = hn::LoadU(df, d_row + tx);
                const auto closer = hn::RebindMask(
                    df, hn::Or(stored_q == zero_i,
                               hn::And(hn::RebindMask(di, z <= stored * tol_hi), q < stored_q)));
                const auto wins = hn::And(active, hn::Or(closer, z < stored * tol_lo));
                if (hn::AllFalse(df, wins)) continue;
                hn::StoreU(hn::DemoteTo(du8, hn::IfThenElse(hn::RebindMask(di, wins), q, stored_q)),
                           du8, q_row + tx);
                hn::StoreU(hn::IfThenElse(wins, z, stored), df, d_row + tx);
                VF tr, tg, tb, ta;
                hn::LoadInterleaved4(df, col_row + 4 * tx, tr, tg, tb, ta);
                hn::StoreInterleaved4(hn::IfThenElse(wins, cr, tr), hn::IfThenElse(wins, cg, tg),
                                      hn::IfThenElse(wins, cb, tb), hn::IfThenElse(wins, ca, ta),
                                      df, col_row + 4 * tx);
                if (has_motion) {
                    float* mo_row = &v.motion.row(row)->x;
                    VF tmx, tmy;
                    hn::LoadInterleaved2(df, mo_row + 2 * tx, tmx, tmy);
                    hn::StoreInterleaved2(hn::IfThenElse(wins, mx, tmx),
                                          hn::IfThenElse(wins, my, tmy), df, mo_row + 2 * tx);
                }
            }
        }
    }
    if (x < sw) splat_row_reference(s, y, x, sw, band);
#endif
}

}  // namespace reprise::warp::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace reprise::warp {

HWY_EXPORT(SplatRowSimd);
HWY_EXPORT(SplatRowRangeSimd);

void splat_row(const SplatScatter& s, int y, const Band& band) {
    HWY_DYNAMIC_DISPATCH(SplatRowSimd)(s, y, band);
}

void splat_row_range(const SplatScatter& s, int y, int& lo, int& hi) {
    HWY_DYNAMIC_DISPATCH(SplatRowRangeSimd)(s, y, lo, hi);
}

}  // namespace reprise::warp
#endif
