// Catmull-Rom lookups that give bicubic_fetch's bits, for the kernels compiled per Highway target
// (simd_kernels.cpp, grid_raster.cpp; both built with -ffp-contract=off): positions, taps and
// weights one lookup a lane, then each lookup's 16 taps four channels a lane, summed in
// bicubic_fetch's order. Lookups whose taps reach past the border are left to bicubic_fetch.
// Included once per target by foreach_target.h, hence the toggled guard.
#if defined(REPRISE_WARP_BICUBIC_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef REPRISE_WARP_BICUBIC_INL_H_
#undef REPRISE_WARP_BICUBIC_INL_H_
#else
#define REPRISE_WARP_BICUBIC_INL_H_
#endif

#include <hwy/highway.h>
#include <cstddef>
#include <cstdint>

#include "reprise/core/image.hpp"

HWY_BEFORE_NAMESPACE();
namespace reprise::warp::HWY_NAMESPACE {

#if HWY_TARGET != HWY_SCALAR

inline constexpr int kBicubicMaxLanes = 16;

// Lane i's lookup: its first tap (column, row) and its weights, x and y, four in a row each.
struct BicubicLanes {
    alignas(64) float wx[4 * kBicubicMaxLanes];
    alignas(64) float wy[4 * kBicubicMaxLanes];
    alignas(64) int32_t x[kBicubicMaxLanes];
    alignas(64) int32_t y[kBicubicMaxLanes];
};

// bicubic_fetch(image, x, y) prepared in every lane (positions finite and well inside the int
// range); true in the lanes whose 16 taps all lie inside a width x height image.
template <class DF>
HWY_INLINE hwy::HWY_NAMESPACE::Mask<DF> BicubicPrepare(DF df, hwy::HWY_NAMESPACE::Vec<DF> x,
                                                       hwy::HWY_NAMESPACE::Vec<DF> y, int width,
                                                       int height, BicubicLanes& out) {
    namespace hn = hwy::HWY_NAMESPACE;
    static_assert(hn::MaxLanes(DF()) <= kBicubicMaxLanes);
    const hn::RebindToSigned<DF> di;
    using VF = hn::Vec<DF>;
    using VI = hn::Vec<decltype(di)>;
    const VF half = hn::Set(df, 0.5f), two = hn::Set(df, 2.0f);
    const VI one = hn::Set(di, 1);
    auto floor_small = [&](VF v) {  // as warp::floor_small
        const VI i = hn::ConvertTo(di, v);
        return hn::IfThenElse(hn::RebindMask(di, v < hn::ConvertTo(df, i)), i - one, i);
    };
    auto weights = [&](VF t, float* w) {  // bicubic_fetch's, in its order
        const VF t2 = t * t, t3 = t2 * t;
        hn::StoreInterleaved4(half * ((hn::Neg(t3) + two * t2) - t),
                              half * ((hn::Set(df, 3.0f) * t3 - hn::Set(df, 5.0f) * t2) + two),
                              half * ((hn::Set(df, -3.0f) * t3 + hn::Set(df, 4.0f) * t2) + t),
                              half * (t3 - t2), df, w);
    };
    const VF sx = x - half, sy = y - half;
    const VI ix = floor_small(sx), iy = floor_small(sy);
    weights(sx - hn::ConvertTo(df, ix), out.wx);
    weights(sy - hn::ConvertTo(df, iy), out.wy);
    hn::StoreU(ix - one, di, out.x);
    hn::StoreU(iy - one, di, out.y);
    // Taps ix - 1 .. ix + 2 and iy - 1 .. iy + 2.
    const VI two_i = hn::Set(di, 2);
    return hn::RebindMask(
        df, hn::And(hn::And(ix > hn::Zero(di), iy > hn::Zero(di)),
                    hn::And(ix + two_i < hn::Set(di, width), iy + two_i < hn::Set(di, height))));
}

// The lookup of lane i, whose taps lie inside `image`: bicubic_fetch's sums, the four channels of
// a tap a lane each.
HWY_INLINE hwy::HWY_NAMESPACE::Vec128<float> BicubicSum(ImageView<const glm::vec4> image,
                                                        const BicubicLanes& l, int i) {
    namespace hn = hwy::HWY_NAMESPACE;
    const hn::Full128<float> d4;
    const float* taps = &(image.row(l.y[i]) + l.x[i])->x;
    const std::ptrdiff_t stride = std::ptrdiff_t(image.stride) * 4;  // floats
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2
    // A row's four taps as two 256-bit pairs; rows j and j + 1 side by side for the sums.
    const hn::Full256<float> d8;
    alignas(32) static constexpr int32_t kFirst[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    alignas(32) static constexpr int32_t kSecond[8] = {2, 2, 2, 2, 3, 3, 3, 3};
    const auto first = hn::SetTableIndices(d8, kFirst), second = hn::SetTableIndices(d8, kSecond);
    const auto wx = hn::LoadDup128(d8, l.wx + 4 * i), wy = hn::LoadDup128(d8, l.wy + 4 * i);
    const auto wx01 = hn::TableLookupLanes(wx, first), wx23 = hn::TableLookupLanes(wx, second);
    const auto zero = hn::Zero(d8);
    auto lines = [&](const float* row) {  // [line of row | line of the next row]
        const auto a = hn::LoadU(d8, row) * wx01, b = hn::LoadU(d8, row + 8) * wx23;
        const auto c = hn::LoadU(d8, row + stride) * wx01;
        const auto e = hn::LoadU(d8, row + stride + 8) * wx23;
        return (((zero + hn::ConcatLowerLower(d8, c, a)) + hn::ConcatUpperUpper(d8, c, a)) +
                hn::ConcatLowerLower(d8, e, b)) +
               hn::ConcatUpperUpper(d8, e, b);
    };
    const auto top = lines(taps) * hn::TableLookupLanes(wy, first);
    const auto bottom = lines(taps + 2 * stride) * hn::TableLookupLanes(wy, second);
    return (((hn::Zero(d4) + hn::LowerHalf(d4, top)) + hn::UpperHalf(d4, top)) +
            hn::LowerHalf(d4, bottom)) +
           hn::UpperHalf(d4, bottom);
#else
    const float* wx = l.wx + 4 * i;
    const float* wy = l.wy + 4 * i;
    auto acc = hn::Zero(d4);
    for (int j = 0; j < 4; ++j) {
        const float* row = taps + j * stride;
        auto line = hn::Zero(d4);
        for (int k = 0; k < 4; ++k) line = line + hn::Set(d4, wx[k]) * hn::LoadU(d4, row + 4 * k);
        acc = acc + hn::Set(d4, wy[j]) * line;
    }
    return acc;
#endif
}

#endif  // HWY_TARGET != HWY_SCALAR

}  // namespace reprise::warp::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#endif  // REPRISE_WARP_BICUBIC_INL_H_
