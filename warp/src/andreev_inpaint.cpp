// Andreev-style inpainting: hole pixels copy the patch mirrored about the hole's edge from the
// four axis directions. Per pass, each row's hole runs give the horizontal sources and two
// run-length tables (swept row by row) the vertical ones, so a pass costs O(pixels).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#include "reprise/core/parallel.hpp"
#include "reprise/warp/fill.hpp"

namespace reprise::warp {

namespace {

using glm::vec3;
using glm::vec4;

// kFilledNow marks pixels filled by the running pass; they count as holes until the row is done.
enum : uint8_t { kHole = 0, kValid = 1, kFilled = 2, kFilledNow = 3 };

bool finite_bits(float f) {
    uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return (u & 0x7f800000u) != 0x7f800000u;
}

float sane_depth(float d) { return std::isnan(d) ? INFINITY : std::max(d, 0.0f); }

// One row of a vertical table from the row before it (`prev`, null for the first row): for a
// hole, the distance to the nearest valid pixel in that direction (0 = none); for a valid pixel,
// the length of the valid run ending at it.
void table_row(const uint8_t* state, const uint8_t* prev_state, const uint16_t* prev, uint16_t* out,
               int width) {
    if (!prev) {
        for (int x = 0; x < width; ++x) out[x] = state[x] != kHole;
        return;
    }
    for (int x = 0; x < width; ++x) {
        const bool v = state[x] != kHole, pv = prev_state[x] != kHole;
        const uint16_t t = prev[x];
        out[x] = v != pv ? uint16_t(1) : uint16_t(t + (t != 0));
    }
}

// Per axis: of two sources nearer/farther than each other by more than the ratio, the nearer
// (the foreground side of a disocclusion) is dropped.
void prefer_background(bool use[4], const float depth[4]) {
    for (int a = 0; a < 4; a += 2) {
        if (!use[a] || !use[a + 1]) continue;
        if (depth[a] * kBackgroundDepthRatio < depth[a + 1])
            use[a] = false;
        else if (depth[a + 1] * kBackgroundDepthRatio < depth[a])
            use[a + 1] = false;
    }
}

template <class T>
void ensure_size(Image<T>& img, int w, int h) {
    if (img.width() != w || img.height() != h) img.resize(w, h);
}

}  // namespace

FillStats AndreevInpaint::fill(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                               ImageView<const float> depth, int max_passes) {
    REPRISE_ASSERT(valid.width == color.width && valid.height == color.height);
    REPRISE_ASSERT(depth.empty() || (depth.width == color.width && depth.height == color.height));
    REPRISE_ASSERT(color.width < 65536 && color.height < 65536);
    FillStats stats;
    if (color.empty()) return stats;
    const int width = color.width, height = color.height;
    const bool use_depth = !depth.empty();
    ensure_size(state_, width, height);
    const int grain = std::max(1, 16384 / width);
    auto state_row = [&](int y) { return state_.data() + std::size_t(y) * width; };

    std::atomic<std::size_t> holes{0};
    parallel_for(
        0, height,
        [&](int y0, int y1) {
            std::size_t count = 0;
            for (int y = y0; y < y1; ++y) {
                uint8_t* st = state_row(y);
                const vec4* c = color.row(y);
                const uint8_t* m = valid.row(y);
                for (int x = 0; x < width; ++x) {
                    const bool ok = (m[x] != 0) & finite_bits(c[x].r) & finite_bits(c[x].g) &
                                    finite_bits(c[x].b);
                    st[x] = ok ? kValid : kHole;
                    count += !ok;
                }
            }
            holes += count;
        },
        grain);
    stats.holes = holes.load();
    std::size_t remaining = stats.holes;
    if (remaining == 0 || remaining == color.pixel_count() || max_passes < 1) {
        stats.unfilled = remaining;
        return stats;
    }
    ensure_size(up_, width, height);
    ensure_size(down_, width, height);
    if (use_depth) ensure_size(filled_depth_, width, height);

    auto source_depth = [&](int x, int y) {
        return state_(x, y) == kValid ? sane_depth(depth(x, y)) : filled_depth_(x, y);
    };
    // Length of the valid run starting at x in direction step, at most `cap`.
    auto run_from = [&](const uint8_t* st, int x, int step, int cap) {
        int n = 0;
        while (n < cap && x >= 0 && x < width && (st[x] == kValid || st[x] == kFilled))
            ++n, x += step;
        return n;
    };

    while (remaining > 0 && stats.levels < max_passes) {
        // Vertical tables, swept row by row in column strips.
        parallel_for(
            0, width,
            [&](int x0, int x1) {
                for (int y = 0; y < height; ++y)
                    table_row(state_row(y) + x0, y ? state_row(y - 1) + x0 : nullptr,
                              y ? &up_(x0, y - 1) : nullptr, &up_(x0, y), x1 - x0);
                for (int y = height - 1; y >= 0; --y)
                    table_row(state_row(y) + x0, y + 1 < height ? state_row(y + 1) + x0 : nullptr,
                              y + 1 < height ? &down_(x0, y + 1) : nullptr, &down_(x0, y), x1 - x0);
            },
            256);

        std::atomic<std::size_t> filled{0};
        parallel_for(
            0, height,
            [&](int y0, int y1) {
                std::size_t count = 0;
                for (int y = y0; y < y1; ++y) {
                    uint8_t* st = state_row(y);
                    int b = 0;
                    while (b < width) {
                        // The next run of holes [a, b) of this row as it was when the pass began.
                        const void* hit = std::memchr(st + b, kHole, std::size_t(width - b));
                        if (!hit) break;
                        const int a = int(static_cast<const uint8_t*>(hit) - st);
                        b = a;
                        while (b < width && st[b] == kHole) ++b;
                        const int run_left = a > 0 ? run_from(st, a - 1, -1, b - a) : 0;
                        const int run_right = b < width ? run_from(st, b, 1, b - a) : 0;
                        for (int x = a; x < b; ++x) {
                            // Sources left, right, up, down; k = 0 where none was found.
                            int sx[4] = {}, sy[4] = {};
                            const int k[4] = {a > 0 ? x - a + 1 : 0, b < width ? b - x : 0,
                                              up_(x, y), down_(x, y)};
                            if (k[0]) sx[0] = a - std::min(k[0], run_left), sy[0] = y;
                            if (k[1]) sx[1] = b - 1 + std::min(k[1], run_right), sy[1] = y;
                            if (k[2]) {
                                const int e = y - k[2];
                                sx[2] = x, sy[2] = e - (std::min(k[2], int(up_(x, e))) - 1);
                            }
                            if (k[3]) {
                                const int e = y + k[3];
                                sx[3] = x, sy[3] = e + (std::min(k[3], int(down_(x, e))) - 1);
                            }
                            if (!(k[0] | k[1] | k[2] | k[3])) continue;
                            bool use[4] = {k[0] > 0, k[1] > 0, k[2] > 0, k[3] > 0};
                            float dk[4] = {}, kept_depth = 0.0f;
                            if (use_depth) {
                                for (int i = 0; i < 4; ++i)
                                    if (use[i]) dk[i] = source_depth(sx[i], sy[i]);
                                prefer_background(use, dk);
                                for (int i = 0; i < 4; ++i)
                                    if (use[i]) kept_depth = std::max(kept_depth, dk[i]);
                            }
                            vec3 acc(0.0f);
                            float wsum = 0.0f;
                            for (int i = 0; i < 4; ++i) {
                                if (!use[i]) continue;
                                const float w = 1.0f / float(k[i]);
                                acc += vec3(color(sx[i], sy[i])) * w;
                                wsum += w;
                            }
                            color(x, y) = vec4(acc / wsum, color(x, y).a);
                            if (use_depth) filled_depth_(x, y) = kept_depth;
                            st[x] = kFilledNow;
                            ++count;
                        }
                    }
                    for (int x = 0; x < width; ++x)
                        if (st[x] == kFilledNow) st[x] = kFilled;
                }
                filled += count;
            },
            grain);
        ++stats.levels;
        remaining -= filled.load();
        if (filled.load() == 0) break;
    }
    stats.unfilled = remaining;
    return stats;
}

FillStats inpaint_andreev(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                          ImageView<const float> depth, int max_passes) {
    AndreevInpaint inpaint;
    return inpaint.fill(color, valid, depth, max_passes);
}

}  // namespace reprise::warp
