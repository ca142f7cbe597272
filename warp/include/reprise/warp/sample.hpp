#pragma once
// Bilinear sampling at pixel coordinates (pixel centres at +0.5), shared by every warp.
#include <algorithm>
#include <cmath>

#include "reprise/core/image.hpp"

namespace reprise::warp {

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
    float fx = std::floor(sx), fy = std::floor(sy);
    b.fx = sx - fx;
    b.fy = sy - fy;
    b.x0 = std::clamp(int(fx), 0, width - 1);
    b.x1 = std::clamp(int(fx) + 1, 0, width - 1);
    b.y0 = std::clamp(int(fy), 0, height - 1);
    b.y1 = std::clamp(int(fy) + 1, 0, height - 1);
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

}  // namespace reprise::warp
