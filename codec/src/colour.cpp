// Linear light <-> 8-bit sRGB display values <-> YCoCg-R planes (lossless integer transform).
#include <algorithm>
#include <array>
#include <cmath>

#include "internal.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::codec {

namespace {

// Linear values at which the 8-bit display code steps up: code = number of thresholds <= v.
const std::array<float, 255>& srgb_thresholds() {
    static const std::array<float, 255> table = [] {
        std::array<float, 255> t{};
        for (int k = 0; k < 255; ++k) t[k] = srgb_to_linear((float(k) + 0.5f) / 255.0f);
        return t;
    }();
    return table;
}

const std::array<float, 256>& srgb_to_linear_table() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int k = 0; k < 256; ++k) t[k] = srgb_to_linear(float(k) / 255.0f);
        return t;
    }();
    return table;
}

// The display code of a linear value: a table over 4096 steps of [0, 1] gives the code at the
// step's start; the thresholds then move it up (at most two steps: the curve is steepest at 0).
struct SrgbEncoder {
    static constexpr int kSteps = 4096;
    const std::array<float, 255>& t = srgb_thresholds();
    std::array<uint8_t, kSteps + 1> start{};

    SrgbEncoder() {
        for (int i = 0; i <= kSteps; ++i)
            start[i] = uint8_t(std::upper_bound(t.begin(), t.end(), float(i) / kSteps) - t.begin());
    }
    int operator()(float v) const {
        if (!(v > 0.0f)) return 0;  // NaN, negative and zero
        if (v >= 1.0f) return 255;
        int code = start[int(v * float(kSteps))];
        while (code < 255 && v >= t[code]) ++code;
        return code;
    }
};

const SrgbEncoder& srgb_encoder() {
    static const SrgbEncoder encoder;
    return encoder;
}

// 4:2:0 chroma tap for full-resolution coordinate x: the nearer sample and the other neighbour.
inline void chroma_taps(int x, int size, int& near, int& other) {
    near = x >> 1;
    other = std::clamp((x & 1) ? near + 1 : near - 1, 0, size - 1);
}

}  // namespace

void planes_from_linear(ImageView<const glm::vec4> color, const SequenceParams& sp, Planes& out) {
    const int w = sp.width, h = sp.height, cw = sp.chroma_width(), ch = sp.chroma_height();
    REPRISE_ASSERT(color.width == w && color.height == h);
    for (int k = 0; k < 3; ++k) ensure_size(out.p[k], sp.plane_width(k), sp.plane_height(k));
    const SrgbEncoder& encode = srgb_encoder();
    const bool sub = sp.chroma == Chroma::C420;
    const int pw = out.p[0].width(), cpw = out.p[1].width();
    // Rows are handled in pairs so that a 4:2:0 chroma row is made by one worker; full-resolution
    // Co and Cg of the pair go to the chroma planes directly (4:4:4) or to a two-row buffer.
    parallel_for(0, (h + 1) / 2, [&](int r0, int r1) {
        std::vector<int16_t> co_rows(sub ? 2 * std::size_t(w) : 0), cg_rows(co_rows.size());
        for (int r = r0; r < r1; ++r) {
            for (int i = 0; i < 2; ++i) {
                const int y = std::min(h - 1, 2 * r + i);
                const glm::vec4* src = color.row(y);
                int16_t* py = out.p[0].data() + std::size_t(y) * pw;
                int16_t* pco = sub ? co_rows.data() + std::size_t(i) * w
                                   : out.p[1].data() + std::size_t(y) * cpw;
                int16_t* pcg = sub ? cg_rows.data() + std::size_t(i) * w
                                   : out.p[2].data() + std::size_t(y) * cpw;
                for (int x = 0; x < w; ++x) {
                    const int R = encode(src[x].r), G = encode(src[x].g), B = encode(src[x].b);
                    const int co = R - B;
                    const int tt = B + (co >> 1);
                    const int cg = G - tt;
                    py[x] = int16_t(tt + (cg >> 1));
                    pco[x] = int16_t(co);
                    pcg[x] = int16_t(cg);
                }
            }
            if (!sub || r >= ch) continue;
            // The rounded mean of each 2x2 block (the last column repeats).
            int16_t* pco = out.p[1].data() + std::size_t(r) * cpw;
            int16_t* pcg = out.p[2].data() + std::size_t(r) * cpw;
            for (int cx = 0; cx < cw; ++cx) {
                const int x0 = 2 * cx, x1 = std::min(w - 1, 2 * cx + 1);
                pco[cx] = int16_t(
                    (co_rows[x0] + co_rows[x1] + co_rows[w + x0] + co_rows[w + x1] + 2) >> 2);
                pcg[cx] = int16_t(
                    (cg_rows[x0] + cg_rows[x1] + cg_rows[w + x0] + cg_rows[w + x1] + 2) >> 2);
            }
        }
    });
    // Padding: the last real column and row repeated.
    for (int k = 0; k < 3; ++k) {
        Image<int16_t>& p = out.p[k];
        const int rw = k ? cw : w, rh = k ? ch : h;
        for (int y = 0; y < rh; ++y)
            for (int x = rw; x < p.width(); ++x) p(x, y) = p(rw - 1, y);
        for (int y = rh; y < p.height(); ++y)
            std::copy(p.data() + std::size_t(rh - 1) * p.width(),
                      p.data() + std::size_t(rh) * p.width(),
                      p.data() + std::size_t(y) * p.width());
    }
}

void linear_from_planes(const Planes& planes, const SequenceParams& sp,
                        ImageView<const float> depth, Image<glm::vec4>& out) {
    const int w = sp.width, h = sp.height, cw = sp.chroma_width(), ch = sp.chroma_height();
    ensure_size(out, w, h);
    const auto& lut = srgb_to_linear_table();
    const bool sub = sp.chroma == Chroma::C420;
    const Image<int16_t>& co_plane = planes.p[1];
    const Image<int16_t>& cg_plane = planes.p[2];
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const int16_t* py = planes.p[0].data() + std::size_t(y) * planes.p[0].width();
            glm::vec4* dst = out.data() + std::size_t(y) * w;
            int cy = y, ny = y;
            if (sub) chroma_taps(y, ch, cy, ny);
            for (int x = 0; x < w; ++x) {
                int co, cg;
                if (sub) {
                    int cx, nx;
                    chroma_taps(x, cw, cx, nx);
                    co = (9 * co_plane(cx, cy) + 3 * co_plane(nx, cy) + 3 * co_plane(cx, ny) +
                          co_plane(nx, ny) + 8) >>
                         4;
                    cg = (9 * cg_plane(cx, cy) + 3 * cg_plane(nx, cy) + 3 * cg_plane(cx, ny) +
                          cg_plane(nx, ny) + 8) >>
                         4;
                } else {
                    co = co_plane(x, y);
                    cg = cg_plane(x, y);
                }
                const int tt = py[x] - (cg >> 1);
                const int G = std::clamp(cg + tt, 0, 255);
                const int B = std::clamp(tt - (co >> 1), 0, 255);
                const int R = std::clamp(tt - (co >> 1) + co, 0, 255);
                float a = 1.0f;
                if (!depth.empty()) a = std::isfinite(depth(x, y)) ? 1.0f : 0.0f;
                dst[x] = {lut[R], lut[G], lut[B], a};
            }
        }
    });
}

}  // namespace reprise::codec
