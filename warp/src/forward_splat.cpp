// Forward splatting: each source pixel scattered along its motion into a z-buffered target.
// Threads draw bands of target rows (band.hpp) and visit only the source rows that can land in
// them, in source order, so every target pixel sees its candidates in the reference's order.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <vector>

#include "reprise/core/parallel.hpp"
#include "reprise/warp/splat.hpp"
#include "splat_kernels.hpp"

namespace reprise::warp {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr int kBandRows = 8;  // a band's scratch stays in a core's cache

bool valid_source(float z, glm::vec2 m) {
    return z >= 0.0f && std::isfinite(m.x) && std::isfinite(m.y);  // z = +inf: background
}

// floor() for values known to lie well inside the int range.
int floor_small(float v) {
    const int i = int(v);
    return float(i) > v ? i - 1 : i;
}

bool land(int x, int y, glm::vec2 m, float factor, int footprint, int w, int h, SplatLanding& out) {
    // In the pixel-centre frame (the centre of pixel i at i).
    const float dx = (float(x) + 0.5f) + factor * m.x - 0.5f;
    const float dy = (float(y) + 0.5f) + factor * m.y - 0.5f;
    // Compared as floats first so that huge positions never reach an int conversion.
    if (!(dx > -1.5f && dy > -1.5f && dx < float(w) + 0.5f && dy < float(h) + 0.5f)) return false;
    if (footprint == 1) {
        const int ix = floor_small(dx + 0.5f), iy = floor_small(dy + 0.5f);
        out = {ix, iy, 1, 1, dx - float(ix), dy - float(iy)};
    } else {
        // A landing within kSnap of a pixel centre covers that pixel alone: otherwise rounding
        // noise in the motion (1e-5 px) would spill a nearer surface one row or column over.
        constexpr float kSnap = 1e-3f;
        const int ix = floor_small(dx + kSnap), iy = floor_small(dy + kSnap);
        const float ox = dx - float(ix), oy = dy - float(iy);
        out = {ix, iy, ox > kSnap ? 2 : 1, oy > kSnap ? 2 : 1, ox, oy};
    }
    return true;
}

// Squared distance from the landing point to a pixel centre, quantised to 1..255 (0 = empty):
// it is kept in the coverage byte until the band is finished.
uint8_t closeness(float ox, float oy) {
    float d2 = ox * ox + oy * oy;  // < 2
    return uint8_t(1 + std::min(254, int(d2 * 127.0f)));
}

}  // namespace

void splat_pixel(const SplatScatter& s, const Band& band, const SplatLanding& l, float z,
                 glm::vec2 m, const glm::vec4& c) {
    const WarpTarget& v = band.view;
    for (int j = 0; j < l.ny; ++j) {
        const int row = l.y0 + j - band.y0;
        if (row < 0 || row >= v.color.height) continue;
        uint8_t* q_row = v.covered.row(row);
        float* d_row = v.depth.row(row);
        for (int i = 0; i < l.nx; ++i) {
            const int tx = l.x0 + i;
            if (tx < 0 || tx >= s.width) continue;
            const uint8_t q = closeness(l.ox - float(i), l.oy - float(j));
            const float stored = d_row[tx];
            const bool wins = q_row[tx] == 0 || z < stored * s.tol_lo ||
                              (z <= stored * s.tol_hi && q < q_row[tx]);
            if (!wins) continue;
            q_row[tx] = q;
            d_row[tx] = z;
            v.color.row(row)[tx] = c;
            if (!v.motion.empty()) v.motion.row(row)[tx] = m;
        }
    }
}

void splat_row_reference(const SplatScatter& s, int y, int x_begin, int x_end, const Band& band) {
    const float* z_row = s.depth.row(y);
    const glm::vec2* m_row = s.motion.row(y);
    const glm::vec4* c_row = s.color.row(y);
    for (int x = x_begin; x < x_end; ++x) {
        const float z = z_row[x];
        const glm::vec2 m = m_row[x];
        if (!valid_source(z, m)) continue;
        SplatLanding l;
        if (land(x, y, m, s.factor, s.footprint, s.width, s.height, l))
            splat_pixel(s, band, l, z, m, c_row[x]);
    }
}

void splat_extent_reference(const SplatScatter& s, int y, int x_begin, int x_end, float& dy_min,
                            float& dy_max) {
    const float* z_row = s.depth.row(y);
    const glm::vec2* m_row = s.motion.row(y);
    for (int x = x_begin; x < x_end; ++x) {
        const float dy = (float(y) + 0.5f) + s.factor * m_row[x].y - 0.5f;  // as in land()
        if (!valid_source(z_row[x], m_row[x]) || !(dy > -1.5f && dy < float(s.height) + 0.5f))
            continue;
        dy_min = std::min(dy_min, dy);
        dy_max = std::max(dy_max, dy);
    }
}

void splat_rows_touched(const SplatScatter& s, float dy_min, float dy_max, int& lo, int& hi) {
    if (dy_min > dy_max) {
        lo = 1;
        hi = 0;
    } else if (s.footprint == 1) {
        lo = floor_small(dy_min + 0.5f);
        hi = floor_small(dy_max + 0.5f);
    } else {
        lo = floor_small(dy_min);
        hi = -floor_small(-dy_max);
    }
}

namespace {

SplatScatter make_scatter(const GBufferView& source, float factor, const WarpTarget& target,
                          const SplatOptions& options) {
    check_warp_inputs(source, target);
    REPRISE_ASSERT(options.footprint == 1 || options.footprint == 2);
    REPRISE_ASSERT(std::isfinite(factor));
    const float tol = std::clamp(options.depth_tolerance, 0.0f, 0.5f);
    return {source.color, source.depth,       source.motion,
            factor,       options.footprint,  1.0f - tol,
            1.0f + tol,   target.color.width, target.color.height};
}

struct Scratch {
    std::vector<glm::vec4> color;
    std::vector<float> depth;
    std::vector<glm::vec2> motion;
    std::vector<uint8_t> covered;
    std::vector<int> ranges;
};

// Per-thread scratch: grown on first use, then reused by every call on that thread.
Scratch& thread_scratch() {
    thread_local Scratch scratch;
    return scratch;
}

}  // namespace

std::size_t splat_refined(const GBufferView& source, float factor, const WarpTarget& target,
                          const SplatOptions& options, BandRefine refine, const void* context) {
    const SplatScatter scatter = make_scatter(source, factor, target, options);
    if (target.color.empty()) return 0;
    const int sh = source.height(), width = target.color.width, height = target.color.height;

    std::vector<int>& ranges = thread_scratch().ranges;  // lo, hi per source row
    if (ranges.size() < std::size_t(2 * sh)) ranges.resize(std::size_t(2 * sh));
    int* range = ranges.data();
    parallel_for(
        0, sh,
        [&](int a, int b) {
            for (int y = a; y < b; ++y) splat_row_range(scatter, y, range[2 * y], range[2 * y + 1]);
        },
        8);

    const int bands = (height + kBandRows - 1) / kBandRows;
    std::atomic<int> next{0};
    std::atomic<std::size_t> covered{0};
    parallel_for(
        0, std::min(thread_count(), bands),
        [&](int a, int b) {
            Scratch& s = thread_scratch();
            for (int k = a; k < b; ++k) {
                std::size_t n = 0;
                for (int i = next++; i < bands; i = next++) {
                    const int y0 = i * kBandRows, rows = std::min(kBandRows, height - y0);
                    const Band band{
                        {scratch_rows(s.color, width, rows), scratch_rows(s.depth, width, rows),
                         target.motion.empty() ? ImageView<glm::vec2>{}
                                               : scratch_rows(s.motion, width, rows),
                         scratch_rows(s.covered, width, rows)},
                        y0};
                    clear_band(band);
                    for (int y = 0; y < sh; ++y)
                        if (range[2 * y] < y0 + rows && range[2 * y + 1] >= y0)
                            splat_row(scatter, y, band);
                    if (refine) refine(band, context);
                    n += copy_band(band, target, kInf);
                }
                covered += n;
            }
        },
        1);
    return covered;
}

std::size_t splat(const GBufferView& source, float factor, const WarpTarget& target,
                  const SplatOptions& options) {
    return splat_refined(source, factor, target, options, nullptr, nullptr);
}

std::size_t splat_reference(const GBufferView& source, float factor, const WarpTarget& target,
                            const SplatOptions& options) {
    const SplatScatter scatter = make_scatter(source, factor, target, options);
    if (target.color.empty()) return 0;
    const Band whole{target, 0};
    clear_band(whole);
    for (int y = 0; y < source.height(); ++y)
        splat_row_reference(scatter, y, 0, source.width(), whole);
    return finish_band(whole, kInf);
}

}  // namespace reprise::warp
