// Forward splatting: each source pixel scattered along its motion into a z-buffered target.
// Threads own bands of target rows and visit only the source rows that can land in them, in
// source order, so every target pixel sees its candidates in the same order as the reference.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <vector>

#include "reprise/core/parallel.hpp"
#include "reprise/warp/splat.hpp"

namespace reprise::warp {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

void check_target(const Frame& source, const WarpTarget& t) {
    REPRISE_ASSERT(source.depth.width() == source.width() && source.depth.height() == source.height());
    REPRISE_ASSERT(source.motion.width() == source.width() && source.motion.height() == source.height());
    REPRISE_ASSERT(t.depth.width == t.color.width && t.depth.height == t.color.height);
    REPRISE_ASSERT(t.covered.width == t.color.width && t.covered.height == t.color.height);
    REPRISE_ASSERT(t.motion.empty() || (t.motion.width == t.color.width && t.motion.height == t.color.height));
}

// Where one source pixel lands: target pixels [x0, x0 + nx) x [y0, y0 + ny), and the offset of
// the landing point from the centre of pixel (x0, y0).
struct Landing {
    int x0, y0, nx, ny;
    float ox, oy;
};

bool valid_source(float z, glm::vec2 m) {
    return z >= 0.0f && std::isfinite(m.x) && std::isfinite(m.y);  // z = +inf: background
}

bool land(int x, int y, glm::vec2 m, float factor, int footprint, int w, int h, Landing& out) {
    float dx = (float(x) + 0.5f) + factor * m.x;
    float dy = (float(y) + 0.5f) + factor * m.y;
    // Pixel-centre frame: centre of pixel i is at i.
    dx -= 0.5f;
    dy -= 0.5f;
    // Compared as floats first so that huge positions never reach an int conversion.
    if (!(dx > -1.5f && dy > -1.5f && dx < float(w) + 0.5f && dy < float(h) + 0.5f)) return false;
    if (footprint == 1) {
        float fx = std::floor(dx + 0.5f), fy = std::floor(dy + 0.5f);
        out = {int(fx), int(fy), 1, 1, dx - fx, dy - fy};
    } else {
        float fx = std::floor(dx), fy = std::floor(dy);
        out = {int(fx), int(fy), dx > fx ? 2 : 1, dy > fy ? 2 : 1, dx - fx, dy - fy};
    }
    return true;
}

// Squared distance from the landing point to a pixel centre, quantised to 1..255 (0 = empty):
// it is kept in the coverage byte until the band is finished.
uint8_t closeness(float ox, float oy) {
    float d2 = ox * ox + oy * oy;  // < 2
    return uint8_t(1 + std::min(254, int(d2 * 127.0f)));
}

struct Scatter {
    const Frame& source;
    const WarpTarget& target;
    float factor;
    int footprint;
    float tol_lo, tol_hi;  // 1 -/+ depth tolerance

    // Offers source pixel (x, y) to the target rows [y_begin, y_end).
    void offer(int x, int y, int y_begin, int y_end) const {
        const float z = source.depth(x, y);
        const glm::vec2 m = source.motion(x, y);
        if (!valid_source(z, m)) return;
        Landing l;
        if (!land(x, y, m, factor, footprint, target.color.width, target.color.height, l)) return;
        for (int j = 0; j < l.ny; ++j) {
            const int ty = l.y0 + j;
            if (ty < y_begin || ty >= y_end) continue;
            for (int i = 0; i < l.nx; ++i) {
                const int tx = l.x0 + i;
                if (tx < 0 || tx >= target.color.width) continue;
                const uint8_t q = closeness(l.ox - float(i), l.oy - float(j));
                uint8_t& stored_q = target.covered(tx, ty);
                float& stored_z = target.depth(tx, ty);
                const bool wins = stored_q == 0 || z < stored_z * tol_lo ||
                                  (z <= stored_z * tol_hi && q < stored_q);
                if (!wins) continue;
                stored_q = q;
                stored_z = z;
                target.color(tx, ty) = source.color(x, y);
                if (!target.motion.empty()) target.motion(tx, ty) = m;
            }
        }
    }

    // Rows of the target that source row y can touch; lo > hi when none.
    void row_range(int y, int& lo, int& hi) const {
        lo = std::numeric_limits<int>::max();
        hi = std::numeric_limits<int>::min();
        for (int x = 0; x < source.width(); ++x) {
            const float z = source.depth(x, y);
            const glm::vec2 m = source.motion(x, y);
            if (!valid_source(z, m)) continue;
            Landing l;
            if (!land(x, y, m, factor, footprint, target.color.width, target.color.height, l)) continue;
            lo = std::min(lo, l.y0);
            hi = std::max(hi, l.y0 + l.ny - 1);
        }
    }
};

void clear_rows(const WarpTarget& t, int y_begin, int y_end) {
    for (int y = y_begin; y < y_end; ++y) {
        std::fill_n(t.depth.row(y), t.depth.width, kInf);
        std::fill_n(t.covered.row(y), t.covered.width, uint8_t(0));
    }
}

// Turns the closeness bytes into coverage, clears what nothing reached, counts the covered.
std::size_t finish_rows(const WarpTarget& t, int y_begin, int y_end) {
    std::size_t count = 0;
    for (int y = y_begin; y < y_end; ++y) {
        uint8_t* covered = t.covered.row(y);
        glm::vec4* color = t.color.row(y);
        glm::vec2* motion = t.motion.empty() ? nullptr : t.motion.row(y);
        for (int x = 0; x < t.color.width; ++x) {
            if (covered[x]) {
                covered[x] = 1;
                ++count;
            } else {
                color[x] = glm::vec4(0.0f);
                if (motion) motion[x] = glm::vec2(0.0f);
            }
        }
    }
    return count;
}

Scatter make_scatter(const Frame& source, float factor, const WarpTarget& target,
                     const SplatOptions& options) {
    check_target(source, target);
    REPRISE_ASSERT(options.footprint == 1 || options.footprint == 2);
    REPRISE_ASSERT(std::isfinite(factor));
    const float tol = std::clamp(options.depth_tolerance, 0.0f, 0.5f);
    return {source, target, factor, options.footprint, 1.0f - tol, 1.0f + tol};
}

}  // namespace

std::size_t splat(const Frame& source, float factor, const WarpTarget& target,
                  const SplatOptions& options) {
    const Scatter scatter = make_scatter(source, factor, target, options);
    const int sh = source.height(), sw = source.width(), th = target.color.height;
    if (target.color.empty()) return 0;

    thread_local std::vector<int> ranges;  // lo, hi per source row
    if (ranges.size() < std::size_t(2 * sh)) ranges.resize(std::size_t(2 * sh));
    int* range = ranges.data();
    parallel_for(0, sh, [&](int a, int b) {
        for (int y = a; y < b; ++y) scatter.row_range(y, range[2 * y], range[2 * y + 1]);
    }, 8);

    std::atomic<std::size_t> covered{0};
    parallel_for(0, th, [&](int y_begin, int y_end) {
        clear_rows(target, y_begin, y_end);
        for (int y = 0; y < sh; ++y) {
            if (range[2 * y] >= y_end || range[2 * y + 1] < y_begin) continue;
            for (int x = 0; x < sw; ++x) scatter.offer(x, y, y_begin, y_end);
        }
        covered += finish_rows(target, y_begin, y_end);
    }, 8);
    return covered;
}

std::size_t splat_reference(const Frame& source, float factor, const WarpTarget& target,
                            const SplatOptions& options) {
    const Scatter scatter = make_scatter(source, factor, target, options);
    const int th = target.color.height;
    if (target.color.empty()) return 0;
    clear_rows(target, 0, th);
    for (int y = 0; y < source.height(); ++y)
        for (int x = 0; x < source.width(); ++x) scatter.offer(x, y, 0, th);
    return finish_rows(target, 0, th);
}

}  // namespace reprise::warp
