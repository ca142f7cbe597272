// Linear light <-> 8-bit sRGB display values <-> YCoCg-R planes (lossless integer transform).
#include <algorithm>
#include <array>
#include <cmath>
#include <type_traits>

#include "internal.hpp"
#include "kernels.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::codec {

namespace {

constexpr int kChunk = 256;  // pixels of a row converted at a time (stack buffers)

// 4:2:0 chroma tap for full-resolution coordinate x: the nearer sample and the other neighbour.
inline void chroma_taps(int x, int size, int& near, int& other) {
    near = x >> 1;
    other = std::clamp((x & 1) ? near + 1 : near - 1, 0, size - 1);
}

}  // namespace

// The display code of a linear value: a table over 4096 steps of [0, 1] gives the code at the
// step's start; the thresholds then move it up (at most one code: the curve is steepest at 0).
const SrgbTables& srgb_tables() {
    static const SrgbTables tables = [] {
        SrgbTables t{};
        for (int k = 0; k < 255; ++k) t.thresholds[k] = srgb_to_linear((float(k) + 0.5f) / 255.0f);
        t.thresholds[255] = INFINITY;
        for (int i = 0; i <= kSrgbSteps; ++i) {
            t.start[i] =
                int32_t(std::upper_bound(t.thresholds, t.thresholds + 255, float(i) / kSrgbSteps) -
                        t.thresholds);
            t.start_threshold[i] = t.thresholds[t.start[i]];
            REPRISE_ASSERT(t.start[i] == 255 ||
                           t.thresholds[t.start[i] + 1] >= float(i + 1) / kSrgbSteps);
        }
        for (int k = 0; k < 256; ++k) t.to_linear[k] = srgb_to_linear(float(k) / 255.0f);
        return t;
    }();
    return tables;
}

namespace {

inline int srgb_code(const SrgbTables& t, float v) {
    if (!(v > 0.0f)) return 0;  // NaN, negative and zero
    if (v >= 1.0f) return 255;
    int code = t.start[int(v * float(kSrgbSteps))];
    while (v >= t.thresholds[code]) ++code;  // thresholds[255] is +inf
    return code;
}

}  // namespace

void to_planes_row_reference(const ToPlanesRow& r, int x_begin, int x_end) {
    const SrgbTables& t = srgb_tables();
    for (int x = x_begin; x < x_end; ++x) {
        int R, G, B;
        if (r.display) {
            R = r.display[x].r, G = r.display[x].g, B = r.display[x].b;
        } else {
            const glm::vec4& c = r.color[x];
            R = srgb_code(t, c.r), G = srgb_code(t, c.g), B = srgb_code(t, c.b);
        }
        const int co = R - B;
        const int tt = B + (co >> 1);
        const int cg = G - tt;
        r.y[x] = int16_t(tt + (cg >> 1));
        r.co[x] = int16_t(co);
        r.cg[x] = int16_t(cg);
    }
}

void from_planes_row_reference(const FromPlanesRow& r, int x_begin, int x_end) {
    const SrgbTables& t = srgb_tables();
    for (int x = x_begin; x < x_end; ++x) {
        const int co = r.co[x], cg = r.cg[x];
        const int tt = r.y[x] - (cg >> 1);
        const int G = std::clamp(cg + tt, 0, 255);
        const int B = std::clamp(tt - (co >> 1), 0, 255);
        const int R = std::clamp(tt - (co >> 1) + co, 0, 255);
        const bool covered = !r.depth || std::isfinite(r.depth[x]);
        if (r.display)
            r.display[x] = {R, G, B, covered ? 255 : 0};
        else
            r.out[x] = {t.to_linear[R], t.to_linear[G], t.to_linear[B], covered ? 1.0f : 0.0f};
    }
}

namespace {

// The source colour: linear light or display codes (one of the two).
struct SourceColor {
    ImageView<const glm::vec4> linear;
    ImageView<const glm::u8vec4> display;
};

void to_planes(const SourceColor& color, const SequenceParams& sp, Planes& out) {
    const int w = sp.width, h = sp.height, cw = sp.chroma_width(), ch = sp.chroma_height();
    REPRISE_ASSERT(color.linear.empty() ? color.display.width == w && color.display.height == h
                                        : color.linear.width == w && color.linear.height == h);
    for (int k = 0; k < 3; ++k) ensure_size(out.p[k], sp.plane_width(k), sp.plane_height(k));
    const bool sub = sp.chroma == Chroma::C420;
    const int pw = out.p[0].width(), cpw = out.p[1].width();
    // Rows are handled in pairs so that a 4:2:0 chroma row is made by one worker; full-resolution
    // Co and Cg of the pair go to the chroma planes directly (4:4:4) or, a chunk of columns at a
    // time, to buffers that are averaged 2x2.
    parallel_for(0, (h + 1) / 2, [&](int r0, int r1) {
        int16_t co_rows[2][kChunk], cg_rows[2][kChunk];
        for (int r = r0; r < r1; ++r)
            for (int x0 = 0; x0 < w; x0 += kChunk) {
                const int n = std::min(kChunk, w - x0);
                for (int i = 0; i < 2; ++i) {
                    const int y = std::min(h - 1, 2 * r + i);
                    int16_t* py = out.p[0].data() + std::size_t(y) * pw + x0;
                    to_planes_row(
                        {.color = color.linear.empty() ? nullptr : color.linear.row(y) + x0,
                         .width = n,
                         .display = color.display.empty() ? nullptr : color.display.row(y) + x0,
                         .y = py,
                         .co = sub ? co_rows[i] : out.p[1].data() + std::size_t(y) * cpw + x0,
                         .cg = sub ? cg_rows[i] : out.p[2].data() + std::size_t(y) * cpw + x0});
                }
                if (!sub || r >= ch) continue;
                // The rounded mean of each 2x2 block (the last column repeats).
                int16_t* pco = out.p[1].data() + std::size_t(r) * cpw;
                int16_t* pcg = out.p[2].data() + std::size_t(r) * cpw;
                for (int cx = x0 / 2; cx < std::min(cw, (x0 + n + 1) / 2); ++cx) {
                    const int a = 2 * cx - x0, b = std::min(w - 1, 2 * cx + 1) - x0;
                    pco[cx] = int16_t(
                        (co_rows[0][a] + co_rows[0][b] + co_rows[1][a] + co_rows[1][b] + 2) >> 2);
                    pcg[cx] = int16_t(
                        (cg_rows[0][a] + cg_rows[0][b] + cg_rows[1][a] + cg_rows[1][b] + 2) >> 2);
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

}  // namespace

void planes_from_linear(ImageView<const glm::vec4> color, const SequenceParams& sp, Planes& out) {
    to_planes({.linear = color}, sp, out);
}

void planes_from_display(ImageView<const glm::u8vec4> color, const SequenceParams& sp,
                         Planes& out) {
    to_planes({.display = color}, sp, out);
}

namespace {

template <class Pixel>
void from_planes(const Planes& planes, const SequenceParams& sp, ImageView<const float> depth,
                 Image<Pixel>& out) {
    const int w = sp.width, h = sp.height, cw = sp.chroma_width(), ch = sp.chroma_height();
    ensure_size(out, w, h);
    const bool sub = sp.chroma == Chroma::C420;
    const Image<int16_t>& co_plane = planes.p[1];
    const Image<int16_t>& cg_plane = planes.p[2];
    parallel_for(0, h, [&](int y0, int y1) {
        int16_t co[kChunk], cg[kChunk];
        int32_t co_column[kChunk / 2 + 2], cg_column[kChunk / 2 + 2];
        for (int y = y0; y < y1; ++y) {
            const int16_t* py = planes.p[0].data() + std::size_t(y) * planes.p[0].width();
            int cy = y, ny = y;
            if (sub) chroma_taps(y, ch, cy, ny);
            for (int x0 = 0; x0 < w; x0 += kChunk) {
                const int n = std::min(kChunk, w - x0);
                const int16_t* pco = co_plane.data() + std::size_t(y) * co_plane.width() + x0;
                const int16_t* pcg = cg_plane.data() + std::size_t(y) * cg_plane.width() + x0;
                if (sub) {
                    // 9 c(x, y) + 3 c(nx, y) + 3 c(x, ny) + c(nx, ny) = 3 v(x) + v(nx) with
                    // v = 3 c(., y) + c(., ny), the vertical pass made once per chroma column.
                    // column[k] holds chroma column c0 - 1 + k, the two ends clamped to the plane
                    // (chroma_taps): pixels 2c and 2c + 1 take c's and their left or right
                    // neighbour's. x0 is even.
                    const int c0 = x0 / 2, m = (n + 1) / 2;
                    const int16_t* co_near = co_plane.data() + std::size_t(cy) * co_plane.width();
                    const int16_t* co_far = co_plane.data() + std::size_t(ny) * co_plane.width();
                    const int16_t* cg_near = cg_plane.data() + std::size_t(cy) * cg_plane.width();
                    const int16_t* cg_far = cg_plane.data() + std::size_t(ny) * cg_plane.width();
                    for (int k = 0; k < m; ++k) {
                        co_column[k + 1] = 3 * co_near[c0 + k] + co_far[c0 + k];
                        cg_column[k + 1] = 3 * cg_near[c0 + k] + cg_far[c0 + k];
                    }
                    const int left = std::max(c0 - 1, 0), right = std::min(c0 + m, cw - 1);
                    co_column[0] = 3 * co_near[left] + co_far[left];
                    cg_column[0] = 3 * cg_near[left] + cg_far[left];
                    co_column[m + 1] = 3 * co_near[right] + co_far[right];
                    cg_column[m + 1] = 3 * cg_near[right] + cg_far[right];
                    // An odd last chunk writes one value past n, inside the buffers (n < kChunk).
                    for (int k = 0; k < m; ++k) {
                        const int co3 = 3 * co_column[k + 1] + 8, cg3 = 3 * cg_column[k + 1] + 8;
                        co[2 * k] = int16_t((co3 + co_column[k]) >> 4);
                        co[2 * k + 1] = int16_t((co3 + co_column[k + 2]) >> 4);
                        cg[2 * k] = int16_t((cg3 + cg_column[k]) >> 4);
                        cg[2 * k + 1] = int16_t((cg3 + cg_column[k + 2]) >> 4);
                    }
                    pco = co, pcg = cg;
                }
                FromPlanesRow row{.y = py + x0,
                                  .co = pco,
                                  .cg = pcg,
                                  .depth = depth.empty() ? nullptr : depth.row(y) + x0,
                                  .width = n,
                                  .out = nullptr};
                if constexpr (std::is_same_v<Pixel, glm::vec4>)
                    row.out = out.data() + std::size_t(y) * w + x0;
                else
                    row.display = out.data() + std::size_t(y) * w + x0;
                from_planes_row(row);
            }
        }
    });
}

}  // namespace

void linear_from_planes(const Planes& planes, const SequenceParams& sp,
                        ImageView<const float> depth, Image<glm::vec4>& out) {
    from_planes(planes, sp, depth, out);
}

void display_from_planes(const Planes& planes, const SequenceParams& sp,
                         ImageView<const float> depth, Image<glm::u8vec4>& out) {
    from_planes(planes, sp, depth, out);
}

}  // namespace reprise::codec
