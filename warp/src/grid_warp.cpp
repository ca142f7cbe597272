// Adaptive-grid warping: a quadtree of cells split at discontinuities (decided on a min/max
// pyramid of each starting cell), vertices moved along the motion, and two triangles per cell
// rasterised with integer edge functions into bands of target rows. Each band visits the cells
// in the same order, so the threaded result equals the single-band reference.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>

#include "reprise/core/parallel.hpp"
#include "reprise/warp/grid_warp.hpp"

namespace reprise::warp {

using detail::GridCell;
using detail::GridRow;
using detail::GridVertex;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kBackgroundDepth = 1e30f;  // background in the depth test
constexpr float kBackgroundFrom = 1e29f;   // depths from here on count as background
constexpr float kHugeMotion = 1e30f;       // motion this large (or NaN/Inf) is invalid
constexpr float kInvalidMotion = 1e38f;    // what invalid motion becomes in a Range
constexpr int kSubpixelBits = 8;           // fixed-point target positions: 1/256 px
constexpr int kSubpixel = 1 << kSubpixelBits;
constexpr float kMaxCoordinate = 1048576.0f;  // 2^20 px; further vertices drop their cell
constexpr int kMaxCell = 64;
constexpr int kBandRows = 16;
constexpr int kOverlap = kSubpixel / 16;   // edges pushed out by 1/16 px (see Rasterizer::edge)

// Depth and motion ranges of a block of pixels. Invalid depth (NaN, negative) enters as -1 and
// invalid motion as kInvalidMotion, so the ranges alone tell whether the block holds any.
struct Range {
    float zmin, zmax, mx0, mx1, my0, my1;

    static Range of(float depth, glm::vec2 m) {
        const float z = depth >= 0.0f ? depth : -1.0f;
        const float mx = std::fabs(m.x) < kHugeMotion ? m.x : kInvalidMotion;
        const float my = std::fabs(m.y) < kHugeMotion ? m.y : kInvalidMotion;
        return {z, z, mx, mx, my, my};
    }
    void add(const Range& o) {
        zmin = std::min(zmin, o.zmin);
        zmax = std::max(zmax, o.zmax);
        mx0 = std::min(mx0, o.mx0);
        mx1 = std::max(mx1, o.mx1);
        my0 = std::min(my0, o.my0);
        my1 = std::max(my1, o.my1);
    }
    bool invalid() const { return zmin < 0.0f || mx1 >= kHugeMotion || my1 >= kHugeMotion; }
};

struct Params {
    float z_ratio;           // 1 + depth_threshold
    float motion_threshold;
    int cell, min_cell;
    float factor;

    bool discontinuous(const Range& r) const {
        return r.invalid() || (r.zmin < kBackgroundFrom && r.zmax >= kBackgroundFrom) ||
               r.zmax > r.zmin * z_ratio || r.mx1 - r.mx0 > motion_threshold ||
               r.my1 - r.my0 > motion_threshold;
    }
};

Params make_params(const GridOptions& o, float factor) {
    REPRISE_ASSERT(std::isfinite(factor));
    Params p{};
    p.min_cell = std::clamp(o.min_cell, 1, 2);
    p.cell = p.min_cell;
    while (p.cell * 2 <= std::min(o.cell, kMaxCell)) p.cell *= 2;
    p.z_ratio = 1.0f + std::max(o.depth_threshold, 0.0f);
    p.motion_threshold = std::max(o.motion_threshold, 0.0f);
    p.factor = factor;
    return p;
}

// Min/max pyramid of one starting cell: level L holds blocks of 2^(L+1) pixels.
struct Pyramid {
    static constexpr int kLevels = 6;  // block sizes 2..64
    Range data[(kMaxCell / 2) * (kMaxCell / 2) * 4 / 3 + 1];
    int offset[kLevels] = {};
    int side[kLevels] = {};

    Range& at(int level, int i, int j) { return data[offset[level] + j * side[level] + i]; }
};

// The first and last pixel whose centre (i + 0.5) lies at or after / at or before a fixed-point
// coordinate (arithmetic shifts round towards -inf).
int first_centre(int64_t v) { return int((v - kSubpixel / 2 + kSubpixel - 1) >> kSubpixelBits); }
int last_centre(int64_t v) { return int((v - kSubpixel / 2) >> kSubpixelBits); }

// Builds the cells of one row of starting cells.
class Builder {
public:
    Builder(const Frame& source, const Params& params)
        : depth_(source.depth.view()), motion_(source.motion.view()), w_(source.width()),
          h_(source.height()), p_(params) {}

    void build_row(int top_row, GridRow& row) {
        row.cells.clear();
        row.y_lo = std::numeric_limits<int>::max();
        row.y_hi = std::numeric_limits<int>::min();
        row_ = &row;
        const int y = top_row * p_.cell;
        for (int x = 0; x < w_; x += p_.cell) {
            x0_ = x;
            y0_ = y;
            if (p_.cell > 1) fill_pyramid();
            subdivide(x, y, p_.cell, level_of(p_.cell));
        }
    }

private:
    static int level_of(int size) {  // 1 -> -1, 2 -> 0, 4 -> 1, ...
        int level = -1;
        for (int block = 2; block <= size; block *= 2) ++level;
        return level;
    }

    void fill_pyramid() {
        const int s = p_.cell;
        int offset = 0;
        for (int level = 0, block = 2; block <= s; ++level, block *= 2) {
            pyr_.offset[level] = offset;
            pyr_.side[level] = s / block;
            offset += (s / block) * (s / block);
        }
        // Blocks reaching past the image repeat its last row or column: same min and max.
        const int side = s / 2;
        for (int j = 0; j < side; ++j) {
            const int ya = std::min(y0_ + 2 * j, h_ - 1), yb = std::min(y0_ + 2 * j + 1, h_ - 1);
            const float* da = depth_.row(ya);
            const float* db = depth_.row(yb);
            const glm::vec2* ma = motion_.row(ya);
            const glm::vec2* mb = motion_.row(yb);
            for (int i = 0; i < side; ++i) {
                const int xa = std::min(x0_ + 2 * i, w_ - 1), xb = std::min(x0_ + 2 * i + 1, w_ - 1);
                Range r = Range::of(da[xa], ma[xa]);
                r.add(Range::of(da[xb], ma[xb]));
                r.add(Range::of(db[xa], mb[xa]));
                r.add(Range::of(db[xb], mb[xb]));
                pyr_.at(0, i, j) = r;
            }
        }
        for (int level = 1, block = 4; block <= s; ++level, block *= 2) {
            for (int j = 0; j < pyr_.side[level]; ++j)
                for (int i = 0; i < pyr_.side[level]; ++i) {
                    Range r = pyr_.at(level - 1, 2 * i, 2 * j);
                    r.add(pyr_.at(level - 1, 2 * i + 1, 2 * j));
                    r.add(pyr_.at(level - 1, 2 * i, 2 * j + 1));
                    r.add(pyr_.at(level - 1, 2 * i + 1, 2 * j + 1));
                    pyr_.at(level, i, j) = r;
                }
        }
    }

    void subdivide(int x, int y, int s, int level) {
        if (x >= w_ || y >= h_) return;
        const Range r = s == 1 ? Range::of(depth_(x, y), motion_(x, y))
                               : pyr_.at(level, (x - x0_) / s, (y - y0_) / s);
        if (s > p_.min_cell && p_.discontinuous(r)) {
            const int half = s / 2;
            subdivide(x, y, half, level - 1);
            subdivide(x + half, y, half, level - 1);
            subdivide(x, y + half, half, level - 1);
            subdivide(x + half, y + half, half, level - 1);
        } else if (!r.invalid()) {
            emit(x, y, std::min(x + s, w_), std::min(y + s, h_));
        }
    }

    struct Sample {
        float z;
        glm::vec2 m;
    };

    Sample pixel(int x, int y) const {
        const float d = depth_(x, y);
        return {d < kBackgroundFrom ? d : kBackgroundDepth, motion_(x, y)};
    }

    // The depth and motion at grid point (cx, cy); (ix, iy) is the cell's pixel nearest to it.
    Sample corner(int cx, int cy, int ix, int iy) const {
        const int xa = std::max(cx - 1, 0), xb = std::min(cx, w_ - 1);
        const int ya = std::max(cy - 1, 0), yb = std::min(cy, h_ - 1);
        const float d[4] = {depth_(xa, ya), depth_(xb, ya), depth_(xa, yb), depth_(xb, yb)};
        const glm::vec2 m[4] = {motion_(xa, ya), motion_(xb, ya), motion_(xa, yb), motion_(xb, yb)};
        Range r = Range::of(d[0], m[0]);
        for (int k = 1; k < 4; ++k) r.add(Range::of(d[k], m[k]));
        if (p_.discontinuous(r)) return pixel(ix, iy);
        const float z = r.zmin < kBackgroundFrom ? ((d[0] + d[1]) + (d[2] + d[3])) * 0.25f : kBackgroundDepth;
        return {z, ((m[0] + m[1]) + (m[2] + m[3])) * 0.25f};
    }

    bool vertex(int cx, int cy, int ix, int iy, GridVertex& v) const {
        const Sample s = corner(cx, cy, ix, iy);
        const float tx = float(cx) + p_.factor * s.m.x;
        const float ty = float(cy) + p_.factor * s.m.y;
        if (!(std::fabs(tx) <= kMaxCoordinate && std::fabs(ty) <= kMaxCoordinate)) return false;
        v = {int32_t(std::lround(double(tx) * kSubpixel)), int32_t(std::lround(double(ty) * kSubpixel)),
             float(cx), float(cy), s.z, s.m.x, s.m.y};
        return true;
    }

    void emit(int x, int y, int x1, int y1) {
        GridCell c;
        if (!vertex(x, y, x, y, c.v[0]) || !vertex(x1, y, x1 - 1, y, c.v[1]) ||
            !vertex(x1, y1, x1 - 1, y1 - 1, c.v[2]) || !vertex(x, y1, x, y1 - 1, c.v[3]))
            return;
        int lo = c.v[0].y, hi = c.v[0].y;
        for (const GridVertex& v : c.v) {
            lo = std::min(lo, v.y);
            hi = std::max(hi, v.y);
        }
        row_->y_lo = std::min(row_->y_lo, first_centre(int64_t(lo) - kOverlap));
        row_->y_hi = std::max(row_->y_hi, last_centre(int64_t(hi) + kOverlap));
        row_->cells.push_back(c);
    }

    ImageView<const float> depth_;
    ImageView<const glm::vec2> motion_;
    int w_, h_;
    Params p_;
    Pyramid pyr_;
    int x0_ = 0, y0_ = 0;
    GridRow* row_ = nullptr;
};

// One attribute as a plane over a triangle: value = at_a + gx (x - a.x) + gy (y - a.y), kept
// within the vertices' range [lo, hi] against rounding.
struct Plane {
    float at_a, gx, gy, lo, hi;
};

class Rasterizer {
public:
    Rasterizer(const Frame& source, const WarpTarget& target)
        : color_(source.color.view()), sw_(source.width()), sh_(source.height()), t_(target),
          motion_(!target.motion.empty()) {}

    void clear(int y_begin, int y_end) const {
        for (int y = y_begin; y < y_end; ++y) {
            std::fill_n(t_.depth.row(y), t_.depth.width, kInf);
            std::fill_n(t_.covered.row(y), t_.covered.width, uint8_t(0));
        }
    }

    void draw_cell(const GridCell& c, int y_begin, int y_end) const {
        int lo = c.v[0].y, hi = c.v[0].y;
        for (const GridVertex& v : c.v) {
            lo = std::min(lo, v.y);
            hi = std::max(hi, v.y);
        }
        if (first_centre(int64_t(lo) - kOverlap) >= y_end || last_centre(int64_t(hi) + kOverlap) < y_begin) return;
        triangle(c.v[0], c.v[1], c.v[2], y_begin, y_end);
        triangle(c.v[0], c.v[2], c.v[3], y_begin, y_end);
    }

    // Background depth back to +inf; holes cleared; returns the covered count.
    std::size_t finish(int y_begin, int y_end) const {
        std::size_t count = 0;
        for (int y = y_begin; y < y_end; ++y) {
            float* depth = t_.depth.row(y);
            const uint8_t* covered = t_.covered.row(y);
            glm::vec4* color = t_.color.row(y);
            glm::vec2* motion = motion_ ? t_.motion.row(y) : nullptr;
            for (int x = 0; x < t_.color.width; ++x) {
                if (covered[x]) {
                    ++count;
                    if (depth[x] >= kBackgroundFrom) depth[x] = kInf;
                } else {
                    color[x] = glm::vec4(0.0f);
                    if (motion) motion[x] = glm::vec2(0.0f);
                }
            }
        }
        return count;
    }

private:
    struct Edge {
        int64_t value;   // at the first pixel centre of the row: inside when >= 0
        int64_t step_x, step_y;
    };

    // Every edge is pushed out by about kOverlap / kSubpixel pixels (measured along the major
    // axis): neighbouring cells overlap slightly and the depth test decides there. That closes
    // the hairline cracks which T-junctions between cells of different sizes and the rounding
    // of vertices to 1/256 px would otherwise leave.
    static Edge edge(const GridVertex& a, const GridVertex& b, int64_t px, int64_t py) {
        const int64_t dx = int64_t(b.x) - a.x, dy = int64_t(b.y) - a.y;
        const int64_t push = kOverlap * std::max(dx < 0 ? -dx : dx, dy < 0 ? -dy : dy);
        return {dx * (py - a.y) - dy * (px - a.x) + push, -dy * kSubpixel, dx * kSubpixel};
    }

    void triangle(const GridVertex& a, const GridVertex& b_in, const GridVertex& c_in, int y_begin,
                  int y_end) const {
        const GridVertex* b = &b_in;
        const GridVertex* c = &c_in;
        int64_t area = (int64_t(b->x) - a.x) * (int64_t(c->y) - a.y) - (int64_t(b->y) - a.y) * (int64_t(c->x) - a.x);
        if (area <= 0) {
            if (area == 0) return;
            std::swap(b, c);
            area = -area;
        }
        // The pushed edges reach kOverlap beyond the vertices' box at most.
        const int x_lo = std::max(0, first_centre(int64_t(std::min({a.x, b->x, c->x})) - kOverlap));
        const int x_hi = std::min(t_.color.width - 1, last_centre(int64_t(std::max({a.x, b->x, c->x})) + kOverlap));
        const int y_lo = std::max(y_begin, first_centre(int64_t(std::min({a.y, b->y, c->y})) - kOverlap));
        const int y_hi = std::min(y_end - 1, last_centre(int64_t(std::max({a.y, b->y, c->y})) + kOverlap));
        if (x_lo > x_hi || y_lo > y_hi) return;

        const int64_t px = int64_t(x_lo) * kSubpixel + kSubpixel / 2, py = int64_t(y_lo) * kSubpixel + kSubpixel / 2;
        Edge e[3] = {edge(a, *b, px, py), edge(*b, *c, px, py), edge(*c, a, px, py)};

        const float scale = 1.0f / kSubpixel;
        const float e1x = float(b->x - a.x) * scale, e1y = float(b->y - a.y) * scale;
        const float e2x = float(c->x - a.x) * scale, e2y = float(c->y - a.y) * scale;
        const float det = e1x * e2y - e2x * e1y;
        auto plane = [&](float va, float vb, float vc) {
            const float d1 = vb - va, d2 = vc - va;
            return Plane{va, (d1 * e2y - d2 * e1y) / det, (d2 * e1x - d1 * e2x) / det,
                         std::min({va, vb, vc}), std::max({va, vb, vc})};
        };
        const Plane pz = plane(a.z, b->z, c->z);
        const Plane psx = plane(a.sx, b->sx, c->sx);
        const Plane psy = plane(a.sy, b->sy, c->sy);
        const Plane pmx = motion_ ? plane(a.mx, b->mx, c->mx) : Plane{};
        const Plane pmy = motion_ ? plane(a.my, b->my, c->my) : Plane{};
        const float ax = float(a.x) * scale, ay = float(a.y) * scale;
        // Source positions kept where the bilinear taps need no clamping: the values there are
        // those of the edge pixels either way.
        const float sx_lo = std::max(psx.lo, 0.5f), sx_hi = std::min(psx.hi, float(sw_) - 0.5f);
        const float sy_lo = std::max(psy.lo, 0.5f), sy_hi = std::min(psy.hi, float(sh_) - 0.5f);
        const bool wide = x_hi - x_lo >= 8;
        float inverse_step[3] = {};
        if (wide)
            for (int k = 0; k < 3; ++k) inverse_step[k] = e[k].step_x ? -1.0f / float(e[k].step_x) : 0.0f;

        for (int y = y_lo; y <= y_hi; ++y, e[0].value += e[0].step_y, e[1].value += e[1].step_y, e[2].value += e[2].step_y) {
            int x_first = x_lo, x_last = x_hi;
            if (wide) {
                // The row's span, estimated in floating point and widened by a pixel each side:
                // the exact test below decides.
                const float room = float(x_hi - x_lo) + 2.0f;
                for (int k = 0; k < 3; ++k) {
                    if (e[k].step_x == 0) {
                        if (e[k].value < 0) x_first = x_hi + 1;
                        continue;
                    }
                    const float bound = std::clamp(float(e[k].value) * inverse_step[k], -2.0f, room);
                    if (e[k].step_x > 0) x_first = std::max(x_first, x_lo + int(std::floor(bound)) - 1);
                    else x_last = std::min(x_last, x_lo + int(std::ceil(bound)) + 1);
                }
                if (x_first > x_last) continue;
            }
            span(e, x_first - x_lo, x_first, x_last, y, ax, ay, pz, psx, psy, pmx, pmy, sx_lo, sx_hi, sy_lo, sy_hi);
        }
    }

    void span(const Edge* e, int skip, int x_first, int x_last, int y, float ax, float ay, const Plane& pz,
              const Plane& psx, const Plane& psy, const Plane& pmx, const Plane& pmy, float sx_lo,
              float sx_hi, float sy_lo, float sy_hi) const {
        const float ox = float(x_first) + 0.5f - ax, oy = float(y) + 0.5f - ay;
        auto start = [&](const Plane& p) { return p.at_a + p.gx * ox + p.gy * oy; };
        float z = start(pz), sx = start(psx), sy = start(psy);
        float mx = motion_ ? start(pmx) : 0.0f, my = motion_ ? start(pmy) : 0.0f;
        int64_t w0 = e[0].value + e[0].step_x * skip, w1 = e[1].value + e[1].step_x * skip,
                w2 = e[2].value + e[2].step_x * skip;
        float* depth = t_.depth.row(y);
        uint8_t* covered = t_.covered.row(y);
        glm::vec4* color = t_.color.row(y);
        glm::vec2* motion = motion_ ? t_.motion.row(y) : nullptr;
        for (int x = x_first; x <= x_last; ++x) {
            if ((w0 | w1 | w2) >= 0) {
                const float zc = std::clamp(z, pz.lo, pz.hi);
                if (zc < depth[x]) {
                    depth[x] = zc;
                    covered[x] = 1;
                    // Bilinear lookup; positions were kept >= 0.5, so truncation is floor.
                    const float fx = std::clamp(sx, sx_lo, sx_hi) - 0.5f;
                    const float fy = std::clamp(sy, sy_lo, sy_hi) - 0.5f;
                    const int x0 = int(fx), y0 = int(fy);
                    const float wx = fx - float(x0), wy = fy - float(y0);
                    const int x1 = std::min(x0 + 1, sw_ - 1), y1 = std::min(y0 + 1, sh_ - 1);
                    const glm::vec4* r0 = color_.row(y0);
                    const glm::vec4* r1 = color_.row(y1);
                    const glm::vec4 top = r0[x0] + (r0[x1] - r0[x0]) * wx;
                    const glm::vec4 bottom = r1[x0] + (r1[x1] - r1[x0]) * wx;
                    color[x] = top + (bottom - top) * wy;
                    if (motion) motion[x] = {std::clamp(mx, pmx.lo, pmx.hi), std::clamp(my, pmy.lo, pmy.hi)};
                }
            }
            w0 += e[0].step_x;
            w1 += e[1].step_x;
            w2 += e[2].step_x;
            z += pz.gx;
            sx += psx.gx;
            sy += psy.gx;
            mx += pmx.gx;
            my += pmy.gx;
        }
    }

    ImageView<const glm::vec4> color_;
    int sw_, sh_;
    const WarpTarget& t_;
    bool motion_;
};

void check(const Frame& source, const WarpTarget& t) {
    REPRISE_ASSERT(source.depth.width() == source.width() && source.depth.height() == source.height());
    REPRISE_ASSERT(source.motion.width() == source.width() && source.motion.height() == source.height());
    REPRISE_ASSERT(t.depth.width == t.color.width && t.depth.height == t.color.height);
    REPRISE_ASSERT(t.covered.width == t.color.width && t.covered.height == t.color.height);
    REPRISE_ASSERT(t.motion.empty() || (t.motion.width == t.color.width && t.motion.height == t.color.height));
}

}  // namespace

GridStats GridWarper::run(const Frame& source, float factor, const WarpTarget& target,
                          const GridOptions& options, bool threaded) {
    check(source, target);
    const Params params = make_params(options, factor);
    GridStats stats;
    if (target.color.empty()) return stats;

    const int top_rows = source.color.empty() ? 0 : (source.height() + params.cell - 1) / params.cell;
    if (int(rows_.size()) < top_rows) rows_.resize(std::size_t(top_rows));
    auto build = [&](int a, int b) {
        Builder builder(source, params);
        for (int r = a; r < b; ++r) builder.build_row(r, rows_[std::size_t(r)]);
    };
    if (threaded) parallel_for(0, top_rows, build, 1);
    else build(0, top_rows);
    for (int r = 0; r < top_rows; ++r) stats.cells += rows_[std::size_t(r)].cells.size();

    const Rasterizer raster(source, target);
    auto draw = [&](int y_begin, int y_end) {
        raster.clear(y_begin, y_end);
        for (int r = 0; r < top_rows; ++r) {
            const GridRow& row = rows_[std::size_t(r)];
            if (row.y_hi < y_begin || row.y_lo >= y_end) continue;
            for (const GridCell& c : row.cells) raster.draw_cell(c, y_begin, y_end);
        }
        return raster.finish(y_begin, y_end);
    };
    const int height = target.color.height;
    if (threaded) {
        std::atomic<std::size_t> covered{0};
        const int bands = (height + kBandRows - 1) / kBandRows;
        parallel_for(0, bands, [&](int a, int b) {
            std::size_t n = 0;
            for (int band = a; band < b; ++band)
                n += draw(band * kBandRows, std::min(height, (band + 1) * kBandRows));
            covered += n;
        }, 1);
        stats.covered = covered;
    } else {
        stats.covered = draw(0, height);
    }
    return stats;
}

GridStats GridWarper::warp(const Frame& source, float factor, const WarpTarget& target,
                           const GridOptions& options) {
    return run(source, factor, target, options, true);
}

GridStats GridWarper::warp_reference(const Frame& source, float factor, const WarpTarget& target,
                                     const GridOptions& options) {
    return run(source, factor, target, options, false);
}

}  // namespace reprise::warp
