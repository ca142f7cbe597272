// The SIMD versions of kernels.hpp, compiled once per Highway target and chosen at run time.
// Each spells out its scalar reference's operations in the same order (no FMA: the codec is
// compiled with -ffp-contract=off), so it gives the same bits; pixels a vector cannot take (the
// end of a row, a filter window over the plane's edge) go through the reference itself.
#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "kernels.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "simd_kernels.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace reprise::codec::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// first, first + 1, ...: Highway 1.0's Iota(d, first) stores the lanes and loads them back, a
// stall in every loop that makes one; the lanes' offsets are made once per call and added.
template <class D, class T>
hn::Vec<D> counting_from(D d, hn::Vec<D> offsets, T first) {
    return offsets + hn::Set(d, hn::TFromD<D>(first));
}

// Lanes where both components of a vector (x, y) are finite: v - v is 0 only for finite v.
template <class V>
auto finite2(V x, V y) {
    const V zero = hn::Zero(hn::DFromV<V>());
    return hn::And((x - x) == zero, (y - y) == zero);
}

void PredictRowSimd(const PredictRow& r) {
    if constexpr (std::endian::native != std::endian::little) {
        predict_row_reference(r, 0, r.width);
        return;
    }
    const hn::ScalableTag<float> df;
    const hn::RebindToSigned<decltype(df)> di;
    const hn::Rebind<int16_t, decltype(df)> d16;
    using VF = hn::Vec<decltype(df)>;
    using VI = hn::Vec<decltype(di)>;
    const int n = int(hn::Lanes(df));
    const auto lane = hn::Iota(df, 0.0f);
    const auto lane_i = hn::Iota(di, 0);
    const VF half = hn::Set(df, 0.5f), eighth = hn::Set(df, 0.125f);
    const VF phases = hn::Set(df, 64.0f);
    const VF x_low = hn::Set(df, -4.0f * 64), x_high = hn::Set(df, float(r.width + 4) * 64);
    // The row's vertical position is the same fixed_position for every lane but its motion.
    const VF y_low = hn::Set(df, -4.0f * 64), y_high = hn::Set(df, float(r.height + 4) * 64);
    const VF cy = hn::Set(df, float(r.y) + 0.5f);
    const VI one = hn::Set(di, 1), two = hn::Set(di, 2), mask63 = hn::Set(di, 63);
    const VI w_minus2 = hn::Set(di, r.width - 2), h_minus2 = hn::Set(di, r.height - 2);
    const VI stride = hn::Set(di, r.width), round = hn::Set(di, 1 << 13);
    const VI lo = hn::Set(di, r.lo), hi = hn::Set(di, r.hi), zero_i = hn::Zero(di);
    const int32_t* base = reinterpret_cast<const int32_t*>(r.reference);
    const VI byte = hn::Set(di, 255), bias = hn::Set(di, kPackedWeightBias);
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3
    // 64 words as four vectors, looked up by phase: two two-table permutes and a blend.
    struct Table64 {
        __m512i t[4];
        explicit Table64(const uint32_t* words) {
            for (int k = 0; k < 4; ++k) t[k] = _mm512_loadu_si512(words + 16 * k);
        }
        VI operator()(VI phase) const {
            const __mmask16 upper = _mm512_test_epi32_mask(phase.raw, _mm512_set1_epi32(32));
            return VI{_mm512_mask_blend_epi32(upper,
                                              _mm512_permutex2var_epi32(t[0], phase.raw, t[1]),
                                              _mm512_permutex2var_epi32(t[2], phase.raw, t[3]))};
        }
    };
    const Table64 packed(catmull_rom_packed());
    auto packed_weights = [&](VI phase) { return packed(phase); };
#else
    // With 16 lanes the 64 packed weights are four vectors, looked up by permutes (a gather
    // each otherwise).
    const int32_t* weights = reinterpret_cast<const int32_t*>(&catmull_rom_packed()[0]);
    const bool permute = n == 16;
    VI table[4] = {zero_i, zero_i, zero_i, zero_i};
    if (permute)
        for (int k = 0; k < 4; ++k) table[k] = hn::LoadU(di, weights + 16 * k);
    const VI fifteen = hn::Set(di, 15), sixteen = hn::Set(di, 16);
    auto packed_weights = [&](VI phase) {
        if (!permute) return hn::GatherIndex(di, weights, phase);
        const auto index = hn::IndicesFromVec(di, hn::And(phase, fifteen));
        const auto odd_table = hn::RebindMask(di, hn::And(phase, sixteen) != zero_i);
        const auto upper_tables = hn::RebindMask(di, hn::And(phase, hn::Set(di, 32)) != zero_i);
        const VI low = hn::IfThenElse(odd_table, hn::TableLookupLanes(table[1], index),
                                      hn::TableLookupLanes(table[0], index));
        const VI high = hn::IfThenElse(odd_table, hn::TableLookupLanes(table[3], index),
                                       hn::TableLookupLanes(table[2], index));
        return hn::IfThenElse(upper_tables, high, low);
    };
#endif

    auto usable = [&](VF& mx, VF& my) {  // non-finite motion counts as 0
        const auto finite = finite2(mx, my);
        mx = hn::IfThenElseZero(finite, mx);
        my = hn::IfThenElseZero(finite, my);
    };
    auto fixed_position = [&](VF centre, VF m, VF low, VF high) {
        const VF q = hn::Min(hn::Max((centre + m - half) * phases, low), high);
        const VI t = hn::ConvertTo(di, q);
        return t - hn::IfThenElseZero(hn::RebindMask(di, q < hn::ConvertTo(df, t)), one);
    };

    // The 16 lanes' windows (taps clamped to the plane) within 32 samples of a row and within two
    // adjacent rows' reach: each row's samples are one load, each lane's tap pairs are permuted out
    // of it (AVX-512BW) and multiplied pairwise; false where they spread wider.
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3
    const bool span_path = n == 16 && r.width >= 32;
    const Table64 pairs01(catmull_rom_pairs()[0]), pairs23(catmull_rom_pairs()[1]);
    const VI last_x = hn::Set(di, r.width - 1), minus_one = hn::Set(di, -1);
    const VI thirty_two = hn::Set(di, 32);
    auto span_sum = [&](VI ix, VI iy, VI px, VI py, VI& sum) {
        if (!span_path) return false;
        auto column = [&](VI c) { return hn::Min(hn::Max(c, zero_i), last_x); };
        const VI c0 = column(ix - one), c3 = column(ix + two);
        // Lanes go left to right: the first's or the last's window is the leftmost.
        const int start =
            std::clamp(std::min(hn::GetLane(c0), hn::ExtractLane(c0, n - 1)), 0, r.width - 32);
        const int top = std::min(hn::GetLane(iy), hn::ExtractLane(iy, n - 1));
        const VI first = hn::Set(di, start), row_offset = iy - hn::Set(di, top);
        const VI c0_in = c0 - first, c3_in = c3 - first;
        if (!hn::AllTrue(di, hn::And(hn::And(c0_in > minus_one, c3_in < thirty_two),
                                     hn::And(row_offset > minus_one, row_offset < two))))
            return false;
        const bool spread = !hn::AllTrue(di, row_offset == zero_i);
        auto pair = [&](VI a, VI b) {
            return hn::Or(hn::And(a, hn::Set(di, 0xffff)), hn::ShiftLeft<16>(b));
        };
        const VI taps01 = pair(c0_in, column(ix) - first);
        const VI taps23 = pair(column(ix + one) - first, c3_in);
        const VI weights01 = pairs01(px), weights23 = pairs23(px);
        auto line = [&](int y) {
            y = std::clamp(y, 0, r.height - 1);
            const __m512i s = _mm512_loadu_si512(r.reference + std::size_t(y) * r.width + start);
            return VI{_mm512_add_epi32(
                _mm512_madd_epi16(_mm512_permutexvar_epi16(taps01.raw, s), weights01.raw),
                _mm512_madd_epi16(_mm512_permutexvar_epi16(taps23.raw, s), weights23.raw))};
        };
        const VI packed_y = packed_weights(py);
        const auto lower = row_offset != zero_i;
        VI above = line(top - 1);
        for (int j = 0; j < 4; ++j) {
            const VI wy = hn::And(hn::ShiftRightSame(packed_y, 8 * j), byte) - bias;
            const VI below = spread ? line(top + j) : above;
            sum = sum + wy * (spread ? hn::IfThenElse(lower, below, above) : above);
            if (j < 3) above = spread ? below : line(top + j);
        }
        return true;
    };
#else
    auto span_sum = [](VI, VI, VI, VI, VI&) { return false; };
#endif

    const int vector_end = std::min(r.width, r.subsampled ? r.motion_width / 2 : r.motion_width);
    int x = 0;
    for (; x + n <= vector_end; x += n) {
        VF mx, my;
        if (!r.subsampled) {
            hn::LoadInterleaved2(df, &r.motion0[x].x, mx, my);
            usable(mx, my);
        } else {
            VF ax, ay, bx, by, cx, cy2, dx, dy;
            hn::LoadInterleaved4(df, &r.motion0[2 * x].x, ax, ay, bx, by);
            hn::LoadInterleaved4(df, &r.motion1[2 * x].x, cx, cy2, dx, dy);
            usable(ax, ay), usable(bx, by), usable(cx, cy2), usable(dx, dy);
            mx = (((ax + bx) + cx) + dx) * eighth;
            my = (((ay + by) + cy2) + dy) * eighth;
        }
        const VF centre = counting_from(df, lane, x) + half;
        const VI qx = fixed_position(centre, mx, x_low, x_high);
        const VI qy = fixed_position(cy, my, y_low, y_high);
        const VI ix = hn::ShiftRight<6>(qx), iy = hn::ShiftRight<6>(qy);
        const auto inside =
            hn::And(hn::And(ix > zero_i, iy > zero_i), hn::And(ix < w_minus2, iy < h_minus2));
        const VI px = hn::And(qx, mask63), py = hn::And(qy, mask63);
        VI sum = zero_i;
        if (!span_sum(ix, iy, px, py, sum)) {
            if (!hn::AllTrue(di, inside)) {  // a window over the edge: the reference clamps
                predict_row_reference(r, x, x + n);
                continue;
            }
            // One lookup per axis fetches a lane's four taps, a biased byte each.
            const VI packed_x = packed_weights(px), packed_y = packed_weights(py);
            const VI wx[4] = {hn::And(packed_x, byte) - bias,
                              hn::And(hn::ShiftRight<8>(packed_x), byte) - bias,
                              hn::And(hn::ShiftRight<16>(packed_x), byte) - bias,
                              hn::And(hn::ShiftRight<24>(packed_x), byte) - bias};
            const VI wy[4] = {hn::And(packed_y, byte) - bias,
                              hn::And(hn::ShiftRight<8>(packed_y), byte) - bias,
                              hn::And(hn::ShiftRight<16>(packed_y), byte) - bias,
                              hn::And(hn::ShiftRight<24>(packed_y), byte) - bias};
            const int ix0 = hn::GetLane(ix), iy0 = hn::GetLane(iy);
            if (hn::AllTrue(
                    di, hn::And(ix == counting_from(di, lane_i, ix0), iy == hn::Set(di, iy0)))) {
                // Adjacent windows: each tap's samples are one contiguous load.
                const int16_t* row = r.reference + std::size_t(iy0 - 1) * r.width + (ix0 - 1);
                for (int j = 0; j < 4; ++j, row += r.width) {
                    const VI line = wx[0] * hn::PromoteTo(di, hn::LoadU(d16, row)) +
                                    wx[1] * hn::PromoteTo(di, hn::LoadU(d16, row + 1)) +
                                    wx[2] * hn::PromoteTo(di, hn::LoadU(d16, row + 2)) +
                                    wx[3] * hn::PromoteTo(di, hn::LoadU(d16, row + 3));
                    sum = sum + wy[j] * line;
                }
            } else {
                // Byte offsets of each window's top-left sample; a 32-bit gather takes two.
                VI offset = hn::ShiftLeft<1>((iy - one) * stride + (ix - one));
                const VI row_bytes = hn::Set(di, 2 * r.width);
                for (int j = 0; j < 4; ++j, offset = offset + row_bytes) {
                    const VI a = hn::GatherOffset(di, base, offset);
                    const VI b = hn::GatherOffset(di, base, offset + two + two);
                    const VI line = wx[0] * hn::ShiftRight<16>(hn::ShiftLeft<16>(a)) +
                                    wx[1] * hn::ShiftRight<16>(a) +
                                    wx[2] * hn::ShiftRight<16>(hn::ShiftLeft<16>(b)) +
                                    wx[3] * hn::ShiftRight<16>(b);
                    sum = sum + wy[j] * line;
                }
            }
        }
        const VI value = hn::ShiftRight<14>(sum + round);
        // Whole-pixel positions (weights 0, 128, 0, 0) copy the sample unclamped.
        const auto whole = hn::And(px == zero_i, py == zero_i);
        const VI out = hn::IfThenElse(whole, value, hn::Min(hn::Max(value, lo), hi));
        hn::StoreU(hn::DemoteTo(d16, out), d16, r.out + x);
    }
    predict_row_reference(r, x, r.width);
}

void BlockDifferencesRowSimd(const BlockDifferencesRow& r) {
    // One block row per vector of 8 lanes; a lane's sum over 8 rows is at most 8 * 510.
    const hn::CappedTag<int16_t, 8> d;
    if (hn::Lanes(d) < 8) {
        block_differences_row_reference(r, 0, r.blocks);
        return;
    }
    HWY_ALIGN int16_t sums[8], largest[8];
    for (int b = 0; b < r.blocks; ++b) {
        const int16_t* s = r.source + 8 * b;
        const int16_t* p = r.prediction + 8 * b;
        auto sum = hn::Zero(d), most = hn::Zero(d);
        for (int y = 0; y < 8; ++y) {
            const auto a = hn::Abs(hn::LoadU(d, s + std::ptrdiff_t(y) * r.stride) -
                                   hn::LoadU(d, p + std::ptrdiff_t(y) * r.stride));
            sum = sum + a;
            most = hn::Max(most, a);
        }
        hn::Store(sum, d, sums);
        hn::Store(most, d, largest);
        int32_t total = 0, top = 0;
        for (int i = 0; i < 8; ++i) total += sums[i], top = std::max<int32_t>(top, largest[i]);
        r.sum[b] = total;
        r.largest[b] = top;
    }
}

void CameraMotionRowSimd(const CameraMotionRow& r) {
    if (!r.perspective) {
        camera_motion_row_reference(r, 0, r.width);
        return;
    }
    const hn::ScalableTag<float> df;
    using VF = hn::Vec<decltype(df)>;
    const int n = int(hn::Lanes(df));
    const auto lane = hn::Iota(df, 0.0f);
    auto splat = [&](float v) { return hn::Set(df, v); };
    const VF a0x = splat(r.a0.x), a0y = splat(r.a0.y), a0w = splat(r.a0.w);
    const VF a1x = splat(r.a1.x), a1y = splat(r.a1.y), a1w = splat(r.a1.w);
    const VF b0x = splat(r.b0.x), b0y = splat(r.b0.y), b0w = splat(r.b0.w);
    const VF b1x = splat(r.b1.x), b1y = splat(r.b1.y), b1w = splat(r.b1.w);
    const VF zero = hn::Zero(df), half = splat(0.5f), one = splat(1.0f);
    const VF inf = splat(std::numeric_limits<float>::infinity());
    const VF nan = splat(std::numeric_limits<float>::quiet_NaN());
    const VF fw = splat(float(r.width)), fh = splat(float(r.height));
    const VF cy = splat(float(r.y) + 0.5f);
    // Background (depth +inf): the direction ((x_ndc wc + p20) / p00, (y_ndc wc + p21) / p11,
    // -1, 0) with wc = -p23, through to_clip as glm multiplies (m0 v0 + m1 v1) + (m2 v2 + m3 v3).
    const glm::mat4& P = r.projection;
    const glm::mat4& M = r.to_clip;
    const VF wc = splat(-P[2][3]), two = splat(2.0f), minus_one = splat(-1.0f);
    const VF bg_y =
        (splat(1.0f - 2.0f * (float(r.y) + 0.5f) / float(r.height)) * wc + splat(P[2][1])) /
        splat(P[1][1]);
    auto bg_clip = [&](int c, VF bg_x) {
        return (splat(M[0][c]) * bg_x + splat(M[1][c]) * bg_y) +
               (splat(M[2][c]) * minus_one + splat(M[3][c]) * zero);
    };
    int x = 0;
    for (; x + n <= r.width; x += n) {
        const VF d = hn::LoadU(df, r.depth + x);
        const auto finite = hn::And(d >= zero, d < inf);
        const auto background = d == inf;
        const VF fx = counting_from(df, lane, x);
        VF cx = (a0x + fx * a1x) + d * (b0x + fx * b1x);
        VF cyc = (a0y + fx * a1y) + d * (b0y + fx * b1y);
        VF cw = (a0w + fx * a1w) + d * (b0w + fx * b1w);
        if (!hn::AllFalse(df, background)) {
            const VF x_ndc = two * (fx + half) / fw - one;
            const VF bg_x = (x_ndc * wc + splat(P[2][0])) / splat(P[0][0]);
            cx = hn::IfThenElse(background, bg_clip(0, bg_x), cx);
            cyc = hn::IfThenElse(background, bg_clip(1, bg_x), cyc);
            cw = hn::IfThenElse(background, bg_clip(3, bg_x), cw);
        }
        // NaN and negative depths have no point: NaN, as for points behind the camera.
        const auto ahead = hn::And(hn::Or(finite, background), cw > zero);
        const VF px = (cx / cw + one) * half * fw;
        const VF py = (one - cyc / cw) * half * fh;
        hn::StoreInterleaved2(hn::IfThenElse(ahead, px - (fx + half), nan),
                              hn::IfThenElse(ahead, py - cy, nan), df, &r.out[x].x);
    }
    camera_motion_row_reference(r, x, r.width);
}

void ToPlanesRowSimd(const ToPlanesRow& r) {
    const hn::ScalableTag<float> df;
    const hn::RebindToSigned<decltype(df)> di;
    const hn::Rebind<int16_t, decltype(df)> d16;
    using VF = hn::Vec<decltype(df)>;
    using VI = hn::Vec<decltype(di)>;
    const int n = int(hn::Lanes(df));
    const SrgbTables& t = srgb_tables();
    const VF zero = hn::Zero(df), one = hn::Set(df, 1.0f), steps = hn::Set(df, float(kSrgbSteps));
    const VI zero_i = hn::Zero(di), one_i = hn::Set(di, 1), top = hn::Set(di, 255);
    auto code = [&](VF v) {
        const auto positive = v > zero, saturated = v >= one;
        const VF inside = hn::IfThenElseZero(hn::AndNot(saturated, positive), v);
        // The step's code, one more from its threshold on (two gathers, neither waits on the
        // other).
        const VI step = hn::ConvertTo(di, inside * steps);
        const VI start = hn::GatherIndex(di, t.start, step);
        const auto up = hn::RebindMask(di, inside >= hn::GatherIndex(df, t.start_threshold, step));
        const VI c = start + hn::IfThenElseZero(up, one_i);
        return hn::IfThenElse(hn::RebindMask(di, saturated), top,
                              hn::IfThenElse(hn::RebindMask(di, positive), c, zero_i));
    };
    const hn::Rebind<uint8_t, decltype(di)> d8;
    int x = 0;
    for (; x + n <= r.width; x += n) {
        VI R, G, B;
        if (r.display) {
            hn::Vec<decltype(d8)> red, green, blue, alpha;
            hn::LoadInterleaved4(d8, &r.display[x].x, red, green, blue, alpha);
            R = hn::PromoteTo(di, red), G = hn::PromoteTo(di, green), B = hn::PromoteTo(di, blue);
        } else {
            VF red, green, blue, alpha;
            hn::LoadInterleaved4(df, &r.color[x].x, red, green, blue, alpha);
            R = code(red), G = code(green), B = code(blue);
        }
        const VI co = R - B;
        const VI tt = B + hn::ShiftRight<1>(co);
        const VI cg = G - tt;
        hn::StoreU(hn::DemoteTo(d16, tt + hn::ShiftRight<1>(cg)), d16, r.y + x);
        hn::StoreU(hn::DemoteTo(d16, co), d16, r.co + x);
        hn::StoreU(hn::DemoteTo(d16, cg), d16, r.cg + x);
    }
    to_planes_row_reference(r, x, r.width);
}

void FromPlanesRowSimd(const FromPlanesRow& r) {
    const hn::ScalableTag<float> df;
    const hn::RebindToSigned<decltype(df)> di;
    const hn::Rebind<int16_t, decltype(df)> d16;
    using VF = hn::Vec<decltype(df)>;
    using VI = hn::Vec<decltype(di)>;
    const int n = int(hn::Lanes(df));
    const float* lut = srgb_tables().to_linear;
    const VI zero_i = hn::Zero(di), top = hn::Set(di, 255);
    const VF zero = hn::Zero(df), one = hn::Set(df, 1.0f);
    auto clamp = [&](VI v) { return hn::Min(hn::Max(v, zero_i), top); };
    const hn::Rebind<uint8_t, decltype(di)> d8;
    int x = 0;
    for (; x + n <= r.width; x += n) {
        const VI y = hn::PromoteTo(di, hn::LoadU(d16, r.y + x));
        const VI co = hn::PromoteTo(di, hn::LoadU(d16, r.co + x));
        const VI cg = hn::PromoteTo(di, hn::LoadU(d16, r.cg + x));
        const VI tt = y - hn::ShiftRight<1>(cg);
        const VI G = clamp(cg + tt);
        const VI B = clamp(tt - hn::ShiftRight<1>(co));
        const VI R = clamp(tt - hn::ShiftRight<1>(co) + co);
        VF alpha = one;
        if (r.depth) {
            const VF d = hn::LoadU(df, r.depth + x);
            alpha = hn::IfThenElseZero((d - d) == zero, one);
        }
        if (r.display) {
            hn::StoreInterleaved4(hn::DemoteTo(d8, R), hn::DemoteTo(d8, G), hn::DemoteTo(d8, B),
                                  hn::DemoteTo(d8, hn::ConvertTo(di, alpha) * top), d8,
                                  &r.display[x].x);
            continue;
        }
        hn::StoreInterleaved4(hn::GatherIndex(df, lut, R), hn::GatherIndex(df, lut, G),
                              hn::GatherIndex(df, lut, B), alpha, df, &r.out[x].x);
    }
    from_planes_row_reference(r, x, r.width);
}

void ForwardRowSimd(const ForwardRow& r) {
    const hn::ScalableTag<float> df;
    const hn::RebindToSigned<decltype(df)> di;
    using VF = hn::Vec<decltype(df)>;
    const int n = int(hn::Lanes(df));
    const auto lane = hn::Iota(df, 0.0f);
    auto splat = [&](float v) { return hn::Set(df, v); };
    const glm::mat4& P = r.projection;
    const glm::mat4& M = r.to_clip;
    const glm::mat4& C = r.to_camera;
    const VF zero = hn::Zero(df), half = splat(0.5f), one = splat(1.0f), two = splat(2.0f);
    const VF inf = splat(std::numeric_limits<float>::infinity());
    const VF fw = splat(float(r.width)), fh = splat(float(r.height));
    const VF y_ndc = splat(1.0f - 2.0f * (float(r.y) + 0.5f) / float(r.height));
    const auto width_i = hn::Set(di, r.width), none = hn::Set(di, -1);
    // Row c of a glm matrix times (vx, vy, zv, 1), summed as glm sums it.
    auto times = [&](const glm::mat4& m, int c, VF vx, VF vy, VF zv) {
        return (splat(m[0][c]) * vx + splat(m[1][c]) * vy) +
               (splat(m[2][c]) * zv + splat(m[3][c]) * one);
    };
    int i = 0;
    for (; i + n <= r.count; i += n) {
        const VF z = hn::LoadU(df, r.depth + i);
        const auto has_point = hn::And(z < inf, z >= zero);
        const VF fx = counting_from(df, lane, r.x0 + i);
        const VF x_ndc = two * (fx + half) / fw - one;
        const VF zv = hn::Neg(z);
        const VF wc = splat(P[2][3]) * zv + splat(P[3][3]);
        const VF vx = (x_ndc * wc - splat(P[2][0]) * zv - splat(P[3][0])) / splat(P[0][0]);
        const VF vy = (y_ndc * wc - splat(P[2][1]) * zv - splat(P[3][1])) / splat(P[1][1]);
        const VF cx = times(M, 0, vx, vy, zv), cy = times(M, 1, vx, vy, zv);
        const VF cw = times(M, 3, vx, vy, zv);
        const VF px = (cx / cw + one) * half * fw;
        const VF py = (one - cy / cw) * half * fh;
        const VF tz = hn::Neg(times(C, 2, vx, vy, zv));
        const auto inside = hn::And(hn::And(px >= zero, py >= zero), hn::And(px < fw, py < fh));
        const auto lands = hn::And(hn::And(has_point, cw > zero), hn::And(inside, tz > zero));
        if (hn::AllFalse(df, lands)) {  // background, say: nothing else is read where -1
            hn::StoreU(none, di, r.slot + i);
            continue;
        }
        const auto slot = hn::ConvertTo(di, py) * width_i + hn::ConvertTo(di, px);
        hn::StoreU(hn::IfThenElse(hn::RebindMask(di, lands), slot, none), di, r.slot + i);
        hn::StoreU(tz, df, r.z + i);
        hn::StoreU(px, df, r.px + i);
        hn::StoreU(py, df, r.py + i);
        if (r.inverse) hn::StoreU(one / tz, df, r.inverse + i);
    }
    forward_row_reference(r, i, r.count);
}

// plane_row_reference, lane by lane over the pixels whose neighbours span pixels away lie in the
// row; each k only while some landed lane has no value yet.
void PlaneRowSimd(const PlaneRow& r) {
    const hn::ScalableTag<float> df;
    const hn::RebindToSigned<decltype(df)> di;
    using VF = hn::Vec<decltype(df)>;
    using VI = hn::Vec<decltype(di)>;
    using MF = hn::Mask<decltype(df)>;
    const int n = int(hn::Lanes(df)), w = r.width, y = r.y;
    const int begin = std::min(w, r.span), end = std::max(begin, w - r.span);
    const VF zero = hn::Zero(df), half = hn::Set(df, 0.5f);
    const VI none = hn::Set(di, -1);
    const MF nothing = hn::FirstN(df, 0);
    const std::size_t row = std::size_t(y) * w;
    int x = begin;
    for (; x + n <= end; x += n) {
        const std::size_t o = row + std::size_t(x);
        const VI slot = hn::LoadU(di, r.slot + o);
        const MF landed = hn::RebindMask(df, slot > none);
        if (hn::AllFalse(df, landed)) continue;
        const VI object = hn::LoadU(di, r.object + o);
        const VF v = hn::LoadU(df, r.inverse + o), px = hn::LoadU(df, r.px + o);
        const VF py = hn::LoadU(df, r.py + o), share = hn::Set(df, kSameSurface) * v;
        VF tolerance = share;  // set for each distance below
        const VF cx = hn::ConvertTo(df, hn::ConvertTo(di, px)) + half;
        const VF cy = hn::ConvertTo(df, hn::ConvertTo(di, py)) + half;
        // The landing at offset `at` (pixels from o) on the same surface.
        auto beside = [&](std::ptrdiff_t at) {
            const VI s = hn::LoadU(di, r.slot + o + at);
            const VI id = hn::LoadU(di, r.object + o + at);
            const VF other = hn::LoadU(df, r.inverse + o + at);
            return hn::And(hn::RebindMask(df, hn::And(s > none, id == object)),
                           hn::Abs(other - v) <= tolerance);
        };
        VF result = hn::LoadU(df, r.z + o);
        MF open = landed;
        for (int k = r.span; k >= 1 && !hn::AllFalse(df, open); k /= 2) {
            tolerance = hn::Max(share, hn::Set(df, r.step * float(k)));
            const std::ptrdiff_t down = std::ptrdiff_t(k) * w;
            const MF right = beside(k), left = hn::AndNot(right, beside(-k));
            const bool has_below = y + k < r.height, has_above = y - k >= 0;
            const MF below = has_below ? beside(down) : nothing;
            const MF above = hn::AndNot(below, has_above ? beside(-down) : nothing);
            MF take = hn::And(open, hn::And(hn::Or(right, left), hn::Or(below, above)));
            if (hn::AllFalse(df, take)) continue;
            // The neighbour at +a where `first`, else at -a (lanes with neither are masked out
            // below); a row that does not exist is not read.
            auto pick = [&](const float* image, MF first, std::ptrdiff_t a, bool has_plus,
                            bool has_minus) {
                const VF plus = hn::LoadU(df, image + o + (has_plus ? a : 0));
                return hn::IfThenElse(first, plus, hn::LoadU(df, image + o - (has_minus ? a : 0)));
            };
            const VF ax = pick(r.px, right, k, true, true) - px;
            const VF ay = pick(r.py, right, k, true, true) - py;
            const VF bx = pick(r.px, below, down, has_below, has_above) - px;
            const VF by = pick(r.py, below, down, has_below, has_above) - py;
            const VF av = pick(r.inverse, right, k, true, true) - v;
            const VF bv = pick(r.inverse, below, down, has_below, has_above) - v;
            const VF det = ax * by - ay * bx;
            take = hn::And(take, hn::Abs(det) >= hn::Set(df, 0.25f * float(k * k)));
            const VF gx = (av * by - bv * ay) / det, gy = (ax * bv - bx * av) / det;
            const VF change = gx * (cx - px) + gy * (cy - py);
            const VF abs_av = hn::Abs(av), abs_bv = hn::Abs(bv);
            const VF largest = hn::IfThenElse(abs_av < abs_bv, abs_bv, abs_av);  // std::max
            VF sum = v + change;
            take = hn::And(take, hn::And(hn::Abs(change) <= largest, sum > zero));
            if (hn::AllFalse(df, take)) continue;
            VF count = hn::Set(df, 1.0f);
            tolerance = hn::Max(share, hn::Set(df, r.step));
            const std::ptrdiff_t adjacent[] = {-1, 1, -std::ptrdiff_t(w), std::ptrdiff_t(w)};
            const bool exists[] = {true, true, y > 0, y + 1 < r.height};
            for (int a = 0; a < 4; ++a) {
                if (!exists[a]) continue;
                const std::ptrdiff_t at = adjacent[a];
                const VF value = hn::LoadU(df, r.inverse + o + at) +
                                 gx * (cx - hn::LoadU(df, r.px + o + at)) +
                                 gy * (cy - hn::LoadU(df, r.py + o + at));
                const MF add = hn::And(beside(at), value > zero);
                sum = hn::IfThenElse(add, sum + value, sum);
                count = hn::IfThenElse(add, count + hn::Set(df, 1.0f), count);
            }
            result = hn::IfThenElse(take, count / sum, result);
            open = hn::AndNot(take, open);
        }
        hn::BlendedStore(result, landed, df, r.out + x);
    }
    plane_row_reference(r, 0, begin);
    plane_row_reference(r, x, w);
}

std::size_t RevealRowSimd(const RevealRow& r) {
    const hn::ScalableTag<float> df;
    const hn::RebindToSigned<decltype(df)> di;
    const hn::Rebind<uint8_t, decltype(df)> d8;
    using VF = hn::Vec<decltype(df)>;
    using VI = hn::Vec<decltype(di)>;
    const int n = int(hn::Lanes(df));
    const auto lane = hn::Iota(df, 0.0f);
    const VF zero = hn::Zero(df), half = hn::Set(df, 0.5f), margin = hn::Set(df, 1.04f);
    const VF width = hn::Set(df, float(r.width)), height = hn::Set(df, float(r.height));
    const VF fy_base = hn::Set(df, float(r.y) + 0.5f);
    const VI stride = hn::Set(di, r.reference_stride), one = hn::Set(di, 1);
    std::size_t count = 0;
    int x = 0;
    for (; x + n <= r.width; x += n) {
        VF mx, my;
        hn::LoadInterleaved2(df, &r.motion[x].x, mx, my);
        const VF fx = (counting_from(df, lane, x) + half) + mx, fy = fy_base + my;
        const auto inside =
            hn::And(hn::And(fx >= zero, fy >= zero), hn::And(fx < width, fy < height));
        // Lanes outside (NaN among them) convert 0 and read pixel 0; they are masked out below.
        const VI at = hn::ConvertTo(di, hn::IfThenElseZero(inside, fy)) * stride +
                      hn::ConvertTo(di, hn::IfThenElseZero(inside, fx));
        const VF landing = hn::GatherIndex(df, r.reference_depth, at);
        const VF depth = hn::LoadU(df, r.depth + x);
        const auto seen = hn::Not(hn::Or(landing * margin < depth, depth * margin < landing));
        const auto revealed = hn::AndNot(seen, inside);
        count += hn::CountTrue(df, revealed);
        const VI flag = hn::IfThenElseZero(hn::RebindMask(di, revealed), one);
        hn::StoreU(hn::DemoteTo(d8, flag), d8, r.out + x);
    }
    return count + reveal_row_reference(r, x, r.width);
}

bool MotionResidualRowSimd(const MotionResidualRow& r) {
    const hn::ScalableTag<float> df;
    using VF = hn::Vec<decltype(df)>;
    const int n = int(hn::Lanes(df));
    const VF zero = hn::Zero(df), half = hn::Set(df, 0.5f), one = hn::Set(df, 1.0f);
    const VF eight = hn::Set(df, 8.0f), limit = hn::Set(df, float(1 << 24));
    // floor(clamp(v) + 0.5) == 0, as residual_of rounds
    auto rounds_to_zero = [&](VF v) {
        const VF t = hn::Min(hn::Max(v, hn::Neg(limit)), limit) + half;
        return hn::And(t >= zero, t < one);
    };
    int x = 0;
    for (; x + n <= r.width; x += n) {
        VF sx, sy, bx, by;
        hn::LoadInterleaved2(df, &r.source[x].x, sx, sy);
        hn::LoadInterleaved2(df, &r.base[x].x, bx, by);
        const auto source_finite = finite2(sx, sy);
        const auto base_finite = finite2(bx, by);
        const VF dx = (sx - hn::IfThenElseZero(base_finite, bx)) * eight;
        const VF dy = (sy - hn::IfThenElseZero(base_finite, by)) * eight;
        const auto zero_residual =
            hn::Or(hn::And(source_finite, hn::And(rounds_to_zero(dx), rounds_to_zero(dy))),
                   hn::AndNot(source_finite, hn::Not(base_finite)));
        if (!hn::AllTrue(df, zero_residual)) return true;
    }
    return motion_residual_row_reference(r, x, r.width);
}

bool MotionWithinRowSimd(const MotionWithinRow& r) {
    const hn::ScalableTag<float> df;
    using VF = hn::Vec<decltype(df)>;
    const int n = int(hn::Lanes(df));
    const VF bound2 = hn::Set(df, r.bound * r.bound);
    int x = 0;
    for (; x + n <= r.width; x += n) {
        VF sx, sy, dx, dy;
        hn::LoadInterleaved2(df, &r.source[x].x, sx, sy);
        hn::LoadInterleaved2(df, &r.decoded[x].x, dx, dy);
        const auto finite = hn::And(finite2(sx, sy), finite2(dx, dy));
        const VF ex = dx - sx, ey = dy - sy;
        const auto close = (ex * ex + ey * ey) <= bound2;
        const auto both_nan = hn::And(hn::IsNaN(sx), hn::IsNaN(dx));
        if (!hn::AllTrue(df, hn::Or(hn::And(finite, close), hn::AndNot(finite, both_nan))))
            return false;
    }
    return motion_within_row_reference(r, x, r.width);
}

ObjectPixels ObjectPixelsRowSimd(const ObjectPixelsRow& r) {
    const hn::ScalableTag<float> df;
    using VF = hn::Vec<decltype(df)>;
    const int n = int(hn::Lanes(df));
    const VF zero = hn::Zero(df), bound2 = hn::Set(df, r.bound * r.bound);
    ObjectPixels total;
    int i = 0;
    for (; i + n <= r.count; i += n) {
        const VF z = hn::LoadU(df, r.depth + i);
        VF mx, my, bx, by;
        hn::LoadInterleaved2(df, &r.motion[i].x, mx, my);
        hn::LoadInterleaved2(df, &r.base[i].x, bx, by);
        const auto usable = hn::And(hn::And(z > zero, (z - z) == zero), finite2(mx, my));
        const VF dx = bx - mx, dy = by - my;
        const auto explained = hn::And(finite2(dx, dy), (dx * dx + dy * dy) <= bound2);
        total.usable += int(hn::CountTrue(df, usable));
        total.unexplained += int(hn::CountTrue(df, hn::AndNot(explained, usable)));
    }
    const ObjectPixels rest = object_pixels_row_reference(r, i, r.count);
    total.usable += rest.usable, total.unexplained += rest.unexplained;
    return total;
}

void ShowsRowSimd(const ShowsRow& r) {
    const hn::ScalableTag<uint32_t> du;
    const hn::RebindToSigned<decltype(du)> di;
    const hn::Rebind<uint8_t, decltype(du)> d8;
    using VU = hn::Vec<decltype(du)>;
    const int n = int(hn::Lanes(du));
    const VU none = hn::Set(du, kNoPrediction), step = hn::Set(du, r.step);
    const VU one = hn::Set(du, 1), two = hn::Set(du, 2), seven = hn::Set(du, 7);
    const auto lane = hn::Iota(du, 0);
    auto apart = [&](VU a, VU b) { return hn::Max(a, b) - hn::Min(a, b) > step; };
    // The first block's pixels by the reference: no vector reads left of the row.
    int i = std::min(r.count, 8);
    shows_row_reference(r, 0, i);
    for (; i + n <= r.count; i += n) {
        const VU t = hn::LoadU(du, r.temporal + i);
        // A depth block's first column (x % 8 == 0: the row starts at x = 0) has no left code.
        const auto first_column =
            hn::And(hn::Add(lane, hn::Set(du, uint32_t(i))), seven) == hn::Zero(du);
        auto stepped = hn::AndNot(first_column, apart(t, hn::LoadU(du, r.temporal + i - 1)));
        if (r.above) stepped = hn::Or(stepped, apart(t, hn::LoadU(du, r.above + i)));
        const VU shows = hn::IfThenElse(t == none, two, hn::IfThenElseZero(stepped, one));
        const VU held = hn::PromoteTo(du, hn::LoadU(d8, r.out + i));
        hn::StoreU(hn::DemoteTo(d8, hn::BitCast(di, hn::Max(held, shows))), d8, r.out + i);
    }
    shows_row_reference(r, i, r.count);
}

void ViewKeepRowSimd(const ViewKeepRow& r) {
    const hn::ScalableTag<double> dd;
    const hn::Rebind<float, decltype(dd)> df;
    const hn::Rebind<int32_t, decltype(dd)> di32;
    const hn::Rebind<int64_t, decltype(dd)> di64;
    using VD = hn::Vec<decltype(dd)>;
    const int n = int(hn::Lanes(dd));
    const VD zero = hn::Zero(dd), one = hn::Set(dd, 1.0), inf = hn::Set(dd, HUGE_VAL);
    const VD step = hn::Set(dd, r.step), half_step = hn::Set(dd, 0.5 * r.step);
    const VD bound = hn::Set(dd, kViewCodesPerStep * r.step),
             displacement = hn::Set(dd, r.displacement);
    const VD codes_per_step = hn::Set(dd, double(kViewCodesPerStep));
    const VD max_code = hn::Set(dd, double(1u << 30));
    int i = 0;
    for (; i + n <= r.count; i += n) {
        const VD z = hn::PromoteTo(dd, hn::LoadU(df, r.source + i));
        // Codes above 2^31 (kNoPrediction) read as negative, those in (2^30, 2^31) above 2^30.
        const VD c = hn::ConvertTo(
            dd,
            hn::PromoteTo(di64, hn::LoadU(di32, reinterpret_cast<const int32_t*>(r.temporal) + i)));
        const VD wc = hn::IfThenElse(c == zero, half_step, c * step);
        const VD w = one / z;
        const VD near = hn::Max(zero, one - displacement * hn::Max(w, wc));
        const VD allowed =
            r.share ? hn::PromoteTo(dd, hn::LoadU(df, r.share + i)) * codes_per_step * step : bound;
        const auto keep =
            hn::And(hn::And(c >= zero, c <= max_code),
                    hn::And(hn::And(z > zero, z < inf), hn::Abs(wc - w) <= allowed * near * near));
        uint8_t bits[HWY_MAX_BYTES / 8 + 8] = {};
        hn::StoreMaskBits(dd, keep, bits);
        for (int k = 0; k < n; ++k) r.keep[i + k] = (bits[k / 8] >> (k % 8)) & 1;
    }
    view_keep_row_reference(r, i, r.count);
}

void ViewCodeRowSimd(const ViewCodeRow& r) {
    const hn::ScalableTag<double> dd;
    const hn::Rebind<float, decltype(dd)> df;
    const hn::Rebind<int32_t, decltype(dd)> di;
    using VD = hn::Vec<decltype(dd)>;
    const int n = int(hn::Lanes(dd));
    const VD one = hn::Set(dd, 1.0);
    const VD step = hn::Set(dd, r.step), max_code = hn::Set(dd, double(kMaxViewCode));
    const auto zero = hn::Zero(df), inf = hn::Set(df, HUGE_VALF), unit = hn::Set(df, 1.0f);
    const auto none = hn::Set(di, int32_t(kNoPrediction));
    const auto background = hn::Set(di, int32_t(kInfCode));
    const auto invalid = hn::Set(di, int32_t(kInvalidCode));
    int i = 0;
    for (; i + n <= r.count; i += n) {
        const auto z = hn::LoadU(df, r.depth + i);
        const auto surface = hn::And(z > zero, z < inf);
        // Lanes that are no surface divide 1 by 1; their code is replaced below.
        const VD zd = hn::PromoteTo(dd, hn::IfThenElse(surface, z, unit));
        const VD k = hn::Min(hn::Round(one / zd / step), max_code);
        auto code = hn::IfThenElse(hn::RebindMask(di, surface), hn::DemoteTo(di, k), invalid);
        code = hn::IfThenElse(hn::RebindMask(di, z == inf), background, code);
        code = hn::IfThenElse(hn::RebindMask(di, hn::IsNaN(z)), none, code);
        hn::StoreU(code, di, reinterpret_cast<int32_t*>(r.out) + i);
    }
    view_code_row_reference(r, i, r.count);
}

void ViewDepthRowSimd(const ViewDepthRow& r) {
    const hn::ScalableTag<double> dd;
    const hn::Rebind<float, decltype(dd)> df;
    const hn::Rebind<int32_t, decltype(dd)> di;
    const hn::Rebind<int64_t, decltype(dd)> di64;
    using VD = hn::Vec<decltype(dd)>;
    const int n = int(hn::Lanes(dd));
    const VD zero = hn::Zero(dd), one = hn::Set(dd, 1.0);
    const VD step = hn::Set(dd, r.step), half_step = hn::Set(dd, 0.5 * r.step);
    const auto max_code = hn::Set(di, int32_t(kMaxViewCode)),
               background = hn::Set(di, int32_t(kInfCode));
    const auto inf = hn::Set(df, HUGE_VALF),
               nan = hn::Set(df, std::numeric_limits<float>::quiet_NaN());
    int i = 0;
    for (; i + n <= r.count; i += n) {
        // Codes above 2^31 read as negative int32: neither a surface's nor the background's.
        const auto c = hn::LoadU(di, reinterpret_cast<const int32_t*>(r.codes) + i);
        const VD cd = hn::ConvertTo(dd, hn::PromoteTo(di64, c));
        const VD w = hn::IfThenElse(cd == zero, half_step, cd * step);
        const auto surface = hn::Not(hn::Or(c<hn::Zero(di), c> max_code));
        auto z = hn::IfThenElse(hn::RebindMask(df, surface), hn::DemoteTo(df, one / w), nan);
        z = hn::IfThenElse(hn::RebindMask(df, c == background), inf, z);
        hn::StoreU(z, df, r.out + i);
    }
    view_depth_row_reference(r, i, r.count);
}

}  // namespace reprise::codec::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace reprise::codec {

HWY_EXPORT(PredictRowSimd);

HWY_EXPORT(CameraMotionRowSimd);
HWY_EXPORT(BlockDifferencesRowSimd);
HWY_EXPORT(ToPlanesRowSimd);
HWY_EXPORT(FromPlanesRowSimd);
HWY_EXPORT(ForwardRowSimd);
HWY_EXPORT(MotionResidualRowSimd);
HWY_EXPORT(MotionWithinRowSimd);
HWY_EXPORT(ObjectPixelsRowSimd);
HWY_EXPORT(ShowsRowSimd);
HWY_EXPORT(ViewKeepRowSimd);
HWY_EXPORT(ViewCodeRowSimd);
HWY_EXPORT(ViewDepthRowSimd);
HWY_EXPORT(PlaneRowSimd);
HWY_EXPORT(RevealRowSimd);

void shows_row(const ShowsRow& row) { HWY_DYNAMIC_DISPATCH(ShowsRowSimd)(row); }

void view_keep_row(const ViewKeepRow& row) { HWY_DYNAMIC_DISPATCH(ViewKeepRowSimd)(row); }

void view_code_row(const ViewCodeRow& row) { HWY_DYNAMIC_DISPATCH(ViewCodeRowSimd)(row); }

void view_depth_row(const ViewDepthRow& row) { HWY_DYNAMIC_DISPATCH(ViewDepthRowSimd)(row); }

bool motion_residual_row(const MotionResidualRow& row) {
    return HWY_DYNAMIC_DISPATCH(MotionResidualRowSimd)(row);
}

bool motion_within_row(const MotionWithinRow& row) {
    return HWY_DYNAMIC_DISPATCH(MotionWithinRowSimd)(row);
}

ObjectPixels object_pixels_row(const ObjectPixelsRow& row) {
    return HWY_DYNAMIC_DISPATCH(ObjectPixelsRowSimd)(row);
}

void plane_row(const PlaneRow& row) { HWY_DYNAMIC_DISPATCH(PlaneRowSimd)(row); }

std::size_t reveal_row(const RevealRow& row) { return HWY_DYNAMIC_DISPATCH(RevealRowSimd)(row); }

void forward_row(const ForwardRow& row) { HWY_DYNAMIC_DISPATCH(ForwardRowSimd)(row); }

void to_planes_row(const ToPlanesRow& row) { HWY_DYNAMIC_DISPATCH(ToPlanesRowSimd)(row); }

void from_planes_row(const FromPlanesRow& row) { HWY_DYNAMIC_DISPATCH(FromPlanesRowSimd)(row); }

void predict_row(const PredictRow& row) { HWY_DYNAMIC_DISPATCH(PredictRowSimd)(row); }

void block_differences_row(const BlockDifferencesRow& row) {
    HWY_DYNAMIC_DISPATCH(BlockDifferencesRowSimd)(row);
}

void camera_motion_row(const CameraMotionRow& row) {
    HWY_DYNAMIC_DISPATCH(CameraMotionRowSimd)(row);
}

}  // namespace reprise::codec
#endif
