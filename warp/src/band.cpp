// Bands of target rows drawn in a per-thread scratch that stays in cache, then written out.
#include "band.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace reprise::warp {

void check_warp_inputs(const GBufferView& source, const WarpTarget& t) {
    REPRISE_ASSERT(source.depth.width == source.width() && source.depth.height == source.height());
    REPRISE_ASSERT(source.motion.width == source.width() &&
                   source.motion.height == source.height());
    REPRISE_ASSERT(t.depth.width == t.color.width && t.depth.height == t.color.height);
    REPRISE_ASSERT(t.covered.width == t.color.width && t.covered.height == t.color.height);
    REPRISE_ASSERT(t.motion.empty() ||
                   (t.motion.width == t.color.width && t.motion.height == t.color.height));
}

namespace {
constexpr float kInf = std::numeric_limits<float>::infinity();

bool finite_color(const glm::vec4& c) {
    return std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z) && std::isfinite(c.w);
}
}  // namespace

void clear_band(const Band& band) {
    const WarpTarget& v = band.view;
    for (int y = 0; y < v.color.height; ++y) {
        std::fill_n(v.depth.row(y), v.depth.width, kInf);
        std::fill_n(v.covered.row(y), v.covered.width, uint8_t(0));
    }
}

std::size_t finish_band(const Band& band, float background_from, std::size_t* nonfinite,
                        bool keep_stretched) {
    const WarpTarget& v = band.view;
    std::size_t count = 0, bad = 0;
    for (int y = 0; y < v.color.height; ++y) {
        float* depth = v.depth.row(y);
        uint8_t* covered = v.covered.row(y);
        glm::vec4* color = v.color.row(y);
        glm::vec2* motion = v.motion.empty() ? nullptr : v.motion.row(y);
        for (int x = 0; x < v.color.width; ++x) {
            if (covered[x]) {
                ++count;
                bad += !finite_color(color[x]);
                covered[x] =
                    keep_stretched && covered[x] == kCoveredStretched ? kCoveredStretched : 1;
                if (depth[x] >= background_from) depth[x] = kInf;
            } else {
                color[x] = glm::vec4(0.0f);
                if (motion) motion[x] = glm::vec2(0.0f);
            }
        }
    }
    if (nonfinite) *nonfinite += bad;
    return count;
}

#if defined(__SSE2__)
namespace {

template <class T>
bool rows_aligned(const ImageView<T>& v) {
    return reinterpret_cast<uintptr_t>(v.data) % 16 == 0 && (v.stride * sizeof(T)) % 16 == 0;
}

// Streaming stores skip reading the output in first: it is larger than any cache.
void put(float* p, __m128 v, bool aligned) {
    if (aligned)
        _mm_stream_ps(p, v);
    else
        _mm_storeu_ps(p, v);
}

}  // namespace
#endif

std::size_t copy_band(const Band& scratch, const WarpTarget& target, float background_from,
                      std::size_t* nonfinite, bool keep_stretched) {
    const WarpTarget& s = scratch.view;
    const bool motion = !target.motion.empty();
    const int width = s.color.width;
    std::size_t count = 0, bad = 0;
#if defined(__SSE2__)
    const bool color_aligned = rows_aligned(target.color),
               depth_aligned = rows_aligned(target.depth);
    const bool motion_aligned = motion && rows_aligned(target.motion);
    const __m128 background = _mm_set1_ps(background_from), inf = _mm_set1_ps(kInf);
    const __m128i zero = _mm_setzero_si128();
    const __m128i exponent = _mm_set1_epi32(0x7f800000);  // all ones: NaN or infinity
#endif
    for (int y = 0; y < s.color.height; ++y) {
        const int ty = scratch.y0 + y;
        const float* sd = s.depth.row(y);
        const uint8_t* sc = s.covered.row(y);
        const glm::vec4* scol = s.color.row(y);
        const glm::vec2* sm = motion ? s.motion.row(y) : nullptr;
        float* td = target.depth.row(ty);
        uint8_t* tc = target.covered.row(ty);
        glm::vec4* tcol = target.color.row(ty);
        glm::vec2* tm = motion ? target.motion.row(ty) : nullptr;
        int x = 0;
#if defined(__SSE2__)
        for (; x + 4 <= width; x += 4) {
            int bytes;
            std::memcpy(&bytes, sc + x, 4);
            const __m128i wide =
                _mm_unpacklo_epi16(_mm_unpacklo_epi8(_mm_cvtsi32_si128(bytes), zero), zero);
            const __m128i set = _mm_cmpgt_epi32(wide, zero);
            const __m128i level =
                keep_stretched
                    ? _mm_min_epi16(wide, _mm_set1_epi32(kCoveredStretched))  // 0, 1 or 2 here
                    : _mm_srli_epi32(set, 31);
            const int ones =
                _mm_cvtsi128_si32(_mm_packus_epi16(_mm_packs_epi32(level, zero), zero));
            std::memcpy(tc + x, &ones, 4);
            const __m128 hit = _mm_castsi128_ps(set);
            constexpr uint8_t kBits[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};
            count += kBits[_mm_movemask_ps(hit)];
            const __m128 z = _mm_loadu_ps(sd + x);
            const __m128 far = _mm_cmpge_ps(z, background);
            put(td + x, _mm_or_ps(_mm_and_ps(far, inf), _mm_andnot_ps(far, z)), depth_aligned);
            const __m128 c0 = _mm_and_ps(_mm_shuffle_ps(hit, hit, 0x00), _mm_loadu_ps(&scol[x].x)),
                         c1 = _mm_and_ps(_mm_shuffle_ps(hit, hit, 0x55),
                                         _mm_loadu_ps(&scol[x + 1].x)),
                         c2 = _mm_and_ps(_mm_shuffle_ps(hit, hit, 0xaa),
                                         _mm_loadu_ps(&scol[x + 2].x)),
                         c3 = _mm_and_ps(_mm_shuffle_ps(hit, hit, 0xff),
                                         _mm_loadu_ps(&scol[x + 3].x));
            put(&tcol[x].x, c0, color_aligned);
            put(&tcol[x + 1].x, c1, color_aligned);
            put(&tcol[x + 2].x, c2, color_aligned);
            put(&tcol[x + 3].x, c3, color_aligned);
            if (nonfinite) {
                const auto special = [&](__m128 c) {
                    const __m128i e = _mm_and_si128(_mm_castps_si128(c), exponent);
                    return _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(e, exponent))) != 0;
                };
                bad += special(c0) + special(c1) + special(c2) + special(c3);
            }
            if (tm) {
                put(&tm[x].x, _mm_and_ps(_mm_unpacklo_ps(hit, hit), _mm_loadu_ps(&sm[x].x)),
                    motion_aligned);
                put(&tm[x + 2].x, _mm_and_ps(_mm_unpackhi_ps(hit, hit), _mm_loadu_ps(&sm[x + 2].x)),
                    motion_aligned);
            }
        }
#endif
        for (; x < width; ++x) {
            const bool hit = sc[x] != 0;
            count += hit;
            tc[x] = !hit ? 0 : keep_stretched && sc[x] == kCoveredStretched ? kCoveredStretched : 1;
            td[x] = sd[x] >= background_from ? kInf : sd[x];
            tcol[x] = hit ? scol[x] : glm::vec4(0.0f);
            bad += hit && !finite_color(scol[x]);
            if (tm) tm[x] = hit ? sm[x] : glm::vec2(0.0f);
        }
    }
    if (nonfinite) *nonfinite += bad;
#if defined(__SSE2__)
    _mm_sfence();  // streaming stores are weakly ordered: make them visible before returning
#endif
    return count;
}

}  // namespace reprise::warp
