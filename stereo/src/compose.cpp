// Stereo pairs as one picture: side by side, top-bottom, red-cyan anaglyph.
#include <algorithm>
#include <cmath>

#include "reprise/core/frame.hpp"
#include "reprise/stereo/compose.hpp"

namespace reprise::stereo {

namespace {

// Red-cyan least-squares anaglyph matrices of E. Dubois ("A projection method to generate
// anaglyph stereo images", ICASSP 2001), as published on his web page for red-cyan glasses.
// They act on linear RGB; rows give the output R, G, B.
constexpr float kDuboisLeft[3][3] = {
    {0.437f, 0.449f, 0.164f}, {-0.062f, -0.062f, -0.024f}, {-0.048f, -0.050f, -0.017f}};
constexpr float kDuboisRight[3][3] = {
    {-0.011f, -0.032f, -0.007f}, {0.377f, 0.761f, 0.009f}, {-0.026f, -0.093f, 1.234f}};

uint8_t encode(float linear) { return uint8_t(std::lround(linear_to_srgb(linear) * 255.0f)); }

glm::vec3 clean(const glm::vec4& c) {
    auto f = [](float v) { return std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : 0.0f; };
    return {f(c.x), f(c.y), f(c.z)};
}

void place(ImageView<const glm::vec4> eye, Image<Rgb8>& out, int x0, int y0) {
    for (int y = 0; y < eye.height; ++y)
        for (int x = 0; x < eye.width; ++x) {
            const glm::vec3 c = clean(eye(x, y));
            out(x0 + x, y0 + y) = Rgb8(encode(c.x), encode(c.y), encode(c.z));
        }
}

}  // namespace

void compose(ImageView<const glm::vec4> left, ImageView<const glm::vec4> right, Layout layout,
             Image<Rgb8>& out) {
    REPRISE_ASSERT(left.width == right.width && left.height == right.height);
    const int w = left.width, h = left.height;
    switch (layout) {
        case Layout::SideBySide:
            out.resize(2 * w, h);
            place(left, out, 0, 0);
            place(right, out, w, 0);
            return;
        case Layout::TopBottom:
            out.resize(w, 2 * h);
            place(left, out, 0, 0);
            place(right, out, 0, h);
            return;
        case Layout::Anaglyph:
            out.resize(w, h);
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const glm::vec3 l = clean(left(x, y)), r = clean(right(x, y));
                    float rgb[3];
                    for (int k = 0; k < 3; ++k)
                        rgb[k] = kDuboisLeft[k][0] * l.x + kDuboisLeft[k][1] * l.y +
                                 kDuboisLeft[k][2] * l.z + kDuboisRight[k][0] * r.x +
                                 kDuboisRight[k][1] * r.y + kDuboisRight[k][2] * r.z;
                    out(x, y) = Rgb8(encode(rgb[0]), encode(rgb[1]), encode(rgb[2]));
                }
            return;
    }
}

}  // namespace reprise::stereo
