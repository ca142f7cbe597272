#pragma once
// Bilinear sampling at pixel coordinates (pixel centres at +0.5), shared by every warp.
#include <algorithm>
#include <cmath>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "reprise/core/image.hpp"

namespace reprise::warp {

// floor() for values well inside the int range, without a libm call (no SSE4.1 in the baseline).
inline int floor_small(float v) {
    const int i = int(v);
    return i - (v < float(i));
}

// The four taps and weights of a bilinear lookup at a continuous position.
struct Bilinear {
    int x0, x1, y0, y1;  // tap columns and rows, clamped to the image
    float fx, fy;        // weights of the x1 column and the y1 row
    bool inside;         // the position lies in the image rectangle [0, W] x [0, H]
};

inline Bilinear bilinear_taps(float x, float y, int width, int height) {
    Bilinear b{0, 0, 0, 0, 0.0f, 0.0f, false};
    // Compared as floats first so that huge or NaN positions never reach an int conversion.
    if (!(x >= 0.0f && y >= 0.0f && x <= float(width) && y <= float(height))) return b;
    float sx = x - 0.5f, sy = y - 0.5f;
    const int ix = floor_small(sx), iy = floor_small(sy);
    b.fx = sx - float(ix);
    b.fy = sy - float(iy);
    b.x0 = std::clamp(ix, 0, width - 1);
    b.x1 = std::clamp(ix + 1, 0, width - 1);
    b.y0 = std::clamp(iy, 0, height - 1);
    b.y1 = std::clamp(iy + 1, 0, height - 1);
    b.inside = true;
    return b;
}

template <class T>
T bilinear_fetch(ImageView<const T> image, const Bilinear& b) {
    const T* r0 = image.row(b.y0);
    const T* r1 = image.row(b.y1);
    T top = r0[b.x0] + (r0[b.x1] - r0[b.x0]) * b.fx;
    T bottom = r1[b.x0] + (r1[b.x1] - r1[b.x0]) * b.fx;
    return top + (bottom - top) * b.fy;
}

// Catmull-Rom (bicubic) sample at a continuous position inside the image, taps clamped to the
// edges: sharper than bilinear (resampling blurs less), may overshoot at edges.
template <class T>
T bicubic_fetch(ImageView<const T> image, float x, float y) {
    float sx = x - 0.5f, sy = y - 0.5f;
    const int ix = floor_small(sx), iy = floor_small(sy);
    float tx = sx - float(ix), ty = sy - float(iy);
    auto weights = [](float t, float w[4]) {
        float t2 = t * t, t3 = t2 * t;
        w[0] = 0.5f * (-t3 + 2.0f * t2 - t);
        w[1] = 0.5f * (3.0f * t3 - 5.0f * t2 + 2.0f);
        w[2] = 0.5f * (-3.0f * t3 + 4.0f * t2 + t);
        w[3] = 0.5f * (t3 - t2);
    };
    float wx[4], wy[4];
    weights(tx, wx);
    weights(ty, wy);
    int x0 = ix - 1, y0 = iy - 1;
    T sum{};
    if (x0 >= 0 && y0 >= 0 && x0 + 3 < image.width && y0 + 3 < image.height) {  // no clamping
#if defined(__SSE2__)
        if constexpr (std::is_same_v<T, glm::vec4>) {  // the same sums, four channels a lane each
            __m128 acc = _mm_setzero_ps();
            for (int j = 0; j < 4; ++j) {
                const float* row = &(image.row(y0 + j) + x0)->x;
                __m128 line = _mm_setzero_ps();
                for (int i = 0; i < 4; ++i)
                    line =
                        _mm_add_ps(line, _mm_mul_ps(_mm_set1_ps(wx[i]), _mm_loadu_ps(row + 4 * i)));
                acc = _mm_add_ps(acc, _mm_mul_ps(_mm_set1_ps(wy[j]), line));
            }
            _mm_storeu_ps(&sum.x, acc);
            return sum;
        }
#endif
        for (int j = 0; j < 4; ++j) {
            const T* row = image.row(y0 + j) + x0;
            T line{};
            for (int i = 0; i < 4; ++i) line += wx[i] * row[i];
            sum += wy[j] * line;
        }
        return sum;
    }
    for (int j = 0; j < 4; ++j) {
        const T* row = image.row(std::clamp(y0 + j, 0, image.height - 1));
        T line{};
        for (int i = 0; i < 4; ++i) line += wx[i] * row[std::clamp(x0 + i, 0, image.width - 1)];
        sum += wy[j] * line;
    }
    return sum;
}

}  // namespace reprise::warp
