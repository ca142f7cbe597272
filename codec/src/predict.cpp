// Inter prediction: every pixel of each plane fetched from the reference picture at p + motion
// with a Catmull-Rom filter in 1/64-pixel integer arithmetic (bit-exact on every machine).
// Whole-pixel motion copies exactly; positions outside the plane clamp to its edge.
#include <algorithm>
#include <array>
#include <cmath>

#include "internal.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::codec {

namespace {

constexpr int kPhases = 64;

// Catmull-Rom weights per phase, in 1/128, summing to 128.
const std::array<std::array<int32_t, 4>, kPhases>& weights() {
    static const auto table = [] {
        std::array<std::array<int32_t, 4>, kPhases> t{};
        for (int p = 0; p < kPhases; ++p) {
            const double f = double(p) / kPhases, f2 = f * f, f3 = f2 * f;
            const double w[4] = {0.5 * (-f3 + 2 * f2 - f), 0.5 * (3 * f3 - 5 * f2 + 2),
                                 0.5 * (-3 * f3 + 4 * f2 + f), 0.5 * (f3 - f2)};
            int sum = 0, largest = 0;
            for (int i = 0; i < 4; ++i) {
                t[p][i] = int32_t(std::lround(w[i] * 128.0));
                sum += t[p][i];
                if (t[p][i] > t[p][largest]) largest = i;
            }
            t[p][largest] += 128 - sum;
        }
        return t;
    }();
    return table;
}

// Sample position in 1/64 of the plane's pixels, of a pixel centre moved by m (plane pixels).
inline int32_t fixed_position(float centre, float m, int size) {
    float q = (centre + m - 0.5f) * float(kPhases);
    q = std::clamp(q, -4.0f * kPhases, float(size + 4) * kPhases);
    const int32_t t = int32_t(q);  // floor without a library call (|q| < 2^21)
    return t - int32_t(q < float(t));
}

inline int sample(const Image<int16_t>& ref, int32_t qx, int32_t qy, int lo, int hi) {
    const int ix = qx >> 6, iy = qy >> 6;
    const auto& wx = weights()[qx & 63];
    const auto& wy = weights()[qy & 63];
    const int w = ref.width(), h = ref.height();
    if ((qx & 63) == 0 && (qy & 63) == 0)
        return ref(std::clamp(ix, 0, w - 1), std::clamp(iy, 0, h - 1));
    int32_t sum = 0;
    if (ix >= 1 && iy >= 1 && ix + 2 < w && iy + 2 < h) {  // the whole 4x4 window inside
        const int16_t* row = ref.data() + std::size_t(iy - 1) * w + (ix - 1);
        for (int j = 0; j < 4; ++j, row += w)
            sum += wy[j] * (wx[0] * row[0] + wx[1] * row[1] + wx[2] * row[2] + wx[3] * row[3]);
        return std::clamp((sum + (1 << 13)) >> 14, lo, hi);
    }
    for (int j = 0; j < 4; ++j) {
        const int16_t* row = ref.data() + std::size_t(std::clamp(iy - 1 + j, 0, h - 1)) * w;
        int32_t line = 0;
        for (int i = 0; i < 4; ++i) line += wx[i] * row[std::clamp(ix - 1 + i, 0, w - 1)];
        sum += wy[j] * line;
    }
    return std::clamp((sum + (1 << 13)) >> 14, lo, hi);
}

inline glm::vec2 usable(glm::vec2 m) {
    return std::isfinite(m.x) && std::isfinite(m.y) ? m : glm::vec2(0.0f);
}

}  // namespace

void predict_planes(const Planes& ref, const SequenceParams& sp, ImageView<const glm::vec2> motion,
                    Planes& out) {
    const int w = sp.width, h = sp.height;
    for (int k = 0; k < 3; ++k) ensure_size(out.p[k], sp.plane_width(k), sp.plane_height(k));
    auto motion_at = [&](int x, int y) {
        return usable(motion(std::min(x, w - 1), std::min(y, h - 1)));
    };
    for (int k = 0; k < 3; ++k) {
        const int s = sp.shift(k), pw = sp.plane_width(k), ph = sp.plane_height(k);
        const int lo = k ? -255 : 0, hi = 255;
        parallel_for(0, ph, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                int16_t* dst = out.p[k].data() + std::size_t(y) * pw;
                for (int x = 0; x < pw; ++x) {
                    glm::vec2 m;
                    if (s == 0) {
                        m = motion_at(x, y);
                    } else {  // mean of the 2x2 luma motions, in chroma pixels
                        m = (motion_at(2 * x, 2 * y) + motion_at(2 * x + 1, 2 * y) +
                             motion_at(2 * x, 2 * y + 1) + motion_at(2 * x + 1, 2 * y + 1)) *
                            0.125f;
                    }
                    dst[x] = int16_t(sample(ref.p[k], fixed_position(float(x) + 0.5f, m.x, pw),
                                            fixed_position(float(y) + 0.5f, m.y, ph), lo, hi));
                }
            }
        });
    }
}

}  // namespace reprise::codec
