// Growing the adaptive grid: each starting cell gets a min/max pyramid of depth and motion, is
// split in four while it holds a discontinuity, and its leaves get vertices moved along the
// motion.
#include <algorithm>
#include <cmath>
#include <vector>

#include "grid_internal.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace reprise::warp::grid {

namespace {

constexpr float kInvalidMotion = 1e38f;       // what invalid motion becomes in a Range
constexpr float kMaxCoordinate = 1048576.0f;  // 2^20 px; further vertices drop their cell

// Depth and motion ranges of a block of pixels. Invalid depth (NaN, negative) enters as -1 and
// invalid motion as kInvalidMotion, so the ranges alone tell whether the block holds any.
struct Range {
    float zmin, zmax;
    glm::vec2 m0, m1;

    static float clean_depth(float d) { return d >= 0.0f ? d : -1.0f; }
    static float clean_motion(float m) { return std::fabs(m) < kHugeMotion ? m : kInvalidMotion; }
    static Range of(float depth, glm::vec2 m) {
        const float z = clean_depth(depth);
        const glm::vec2 c{clean_motion(m.x), clean_motion(m.y)};
        return {z, z, c, c};
    }
    void add(const Range& o) {
        zmin = std::min(zmin, o.zmin);
        zmax = std::max(zmax, o.zmax);
        m0 = {std::min(m0.x, o.m0.x), std::min(m0.y, o.m0.y)};
        m1 = {std::max(m1.x, o.m1.x), std::max(m1.y, o.m1.y)};
    }
    bool invalid() const { return zmin < 0.0f || m1.x >= kHugeMotion || m1.y >= kHugeMotion; }
    bool discontinuous(const Params& p) const {
        return invalid() || (zmin < kBackgroundFrom && zmax >= kBackgroundFrom) ||
               zmax > zmin * p.z_ratio || m1.x - m0.x > p.motion_threshold ||
               m1.y - m0.y > p.motion_threshold;
    }
};

// Min/max ranges of blocks, one array per field.
struct Ranges {
    float* zmin;
    float* zmax;
    glm::vec2* m0;
    glm::vec2* m1;

    Range get(int k) const { return {zmin[k], zmax[k], m0[k], m1[k]}; }
    void set(int k, const Range& r) const {
        zmin[k] = r.zmin;
        zmax[k] = r.zmax;
        m0[k] = r.m0;
        m1[k] = r.m1;
    }
};

#if defined(__SSE2__)
// Level 0 of one row pair, four 2x2 blocks (eight pixels) a step; `blocks` is a multiple of 4 and
// every pixel lies in the image. Same ranges as Range::of and Range::add (up to the sign of zeros).
void base_row_sse2(const float* da, const float* db, const glm::vec2* ma, const glm::vec2* mb,
                   int blocks, float* zmin, float* zmax, glm::vec2* m0, glm::vec2* m1) {
    const __m128 zero = _mm_setzero_ps(), minus_one = _mm_set1_ps(-1.0f);
    const __m128 huge = _mm_set1_ps(kHugeMotion), invalid = _mm_set1_ps(kInvalidMotion);
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    auto select = [](__m128 ok, __m128 a, __m128 b) {
        return _mm_or_ps(_mm_and_ps(ok, a), _mm_andnot_ps(ok, b));
    };
    auto clean_z = [&](const float* p) {
        const __m128 z = _mm_loadu_ps(p);
        return select(_mm_cmpge_ps(z, zero), z, minus_one);
    };
    auto clean_m = [&](const glm::vec2* p) {
        const __m128 m = _mm_loadu_ps(&p->x);
        return select(_mm_cmplt_ps(_mm_and_ps(m, abs_mask), huge), m, invalid);
    };
    constexpr int even = _MM_SHUFFLE(2, 0, 2, 0), odd = _MM_SHUFFLE(3, 1, 3, 1);
    constexpr int low = _MM_SHUFFLE(1, 0, 1, 0), high = _MM_SHUFFLE(3, 2, 3, 2);
    for (int i = 0; i < blocks; i += 4) {
        const int x = 2 * i;
        const __m128 a0 = clean_z(da + x), a1 = clean_z(da + x + 4);
        const __m128 b0 = clean_z(db + x), b1 = clean_z(db + x + 4);
        const __m128 lo0 = _mm_min_ps(a0, b0), lo1 = _mm_min_ps(a1, b1);
        const __m128 hi0 = _mm_max_ps(a0, b0), hi1 = _mm_max_ps(a1, b1);
        _mm_storeu_ps(zmin + i,
                      _mm_min_ps(_mm_shuffle_ps(lo0, lo1, even), _mm_shuffle_ps(lo0, lo1, odd)));
        _mm_storeu_ps(zmax + i,
                      _mm_max_ps(_mm_shuffle_ps(hi0, hi1, even), _mm_shuffle_ps(hi0, hi1, odd)));
        for (int k = 0; k < 4; k += 2) {  // blocks i + k and i + k + 1: (x, y) of two pixels each
            const int p = x + 2 * k;
            const __m128 u0 = clean_m(ma + p), u1 = clean_m(ma + p + 2);
            const __m128 v0 = clean_m(mb + p), v1 = clean_m(mb + p + 2);
            const __m128 mn0 = _mm_min_ps(u0, v0), mn1 = _mm_min_ps(u1, v1);
            const __m128 mx0 = _mm_max_ps(u0, v0), mx1 = _mm_max_ps(u1, v1);
            _mm_storeu_ps(&m0[i + k].x, _mm_min_ps(_mm_shuffle_ps(mn0, mn1, low),
                                                   _mm_shuffle_ps(mn0, mn1, high)));
            _mm_storeu_ps(&m1[i + k].x, _mm_max_ps(_mm_shuffle_ps(mx0, mx1, low),
                                                   _mm_shuffle_ps(mx0, mx1, high)));
        }
    }
}
#endif

// A float to fixed point, rounded to nearest (ties up); |v| <= 2^20.
int32_t to_fixed(float v) {
    const double scaled = double(v) * kSubpixel + 0.5;
    int64_t i = int64_t(scaled);
    if (double(i) > scaled) --i;
    return int32_t(i);
}

// Grows the cells of one row of starting cells. Level 0 of the min/max pyramid (2x2 blocks) is
// filled for the whole row at once, reading the frame row by row; the levels above it are
// filled per starting cell: level L holds blocks of 2^(L+1) pixels.
class Builder {
  public:
    Builder(const Frame& source, const Params& params, bool simd, Scratch& scratch)
        : depth_(source.depth.view()),
          motion_(source.motion.view()),
          w_(source.width()),
          h_(source.height()),
          p_(params),
          simd_(simd),
          base_blocks_((w_ + 1) / 2) {
        const std::size_t n = std::size_t(base_blocks_) * std::size_t(std::max(p_.cell / 2, 1));
        if (scratch.zmin.size() < n) {
            scratch.zmin.resize(n);
            scratch.zmax.resize(n);
            scratch.m0.resize(n);
            scratch.m1.resize(n);
        }
        base_ = {scratch.zmin.data(), scratch.zmax.data(), scratch.m0.data(), scratch.m1.data()};
        int offset = 0;
        for (int level = 1, block = 4; block <= p_.cell; ++level, block *= 2) {
            offset_[level] = offset;
            side_[level] = p_.cell / block;
            offset += side_[level] * side_[level];
        }
        upper_ = {zmin_, zmax_, m0_, m1_};
        lattice_ = p_.cell / p_.min_cell + 1;
        const std::size_t points = std::size_t(lattice_) * std::size_t(lattice_);
        if (scratch.point_state.size() < points) {
            scratch.point_state.resize(points);
            scratch.points.resize(points);
        }
        state_ = scratch.point_state.data();
        shared_ = scratch.points.data();
    }

    void build_row(int top_row, Row& row) {
        row.cells.clear();
        row.y_lo = std::numeric_limits<int>::max();
        row.y_hi = std::numeric_limits<int>::min();
        row_ = &row;
        y0_ = top_row * p_.cell;
        if (p_.cell > 1) fill_base();
        int top_level = -1;
        for (int block = 2; block <= p_.cell; block *= 2) ++top_level;
        for (x0_ = 0; x0_ < w_; x0_ += p_.cell) {
            std::fill_n(state_, lattice_ * lattice_, kUnknown);
            fill_upper();
            subdivide(x0_, y0_, p_.cell, top_level);
        }
    }

  private:
    // Blocks reaching past the image repeat its last row or column: same min and max.
    void fill_base() {
        for (int j = 0; j < p_.cell / 2; ++j) {
            const int ya = std::min(y0_ + 2 * j, h_ - 1), yb = std::min(y0_ + 2 * j + 1, h_ - 1);
            const float* da = depth_.row(ya);
            const float* db = depth_.row(yb);
            const glm::vec2* ma = motion_.row(ya);
            const glm::vec2* mb = motion_.row(yb);
            const int k = j * base_blocks_;
            int i = 0;
#if defined(__SSE2__)
            if (simd_) {
                i = (w_ / 2) / 4 * 4;  // whole blocks, four at a time
                base_row_sse2(da, db, ma, mb, i, base_.zmin + k, base_.zmax + k, base_.m0 + k,
                              base_.m1 + k);
            }
#endif
            for (; i < base_blocks_; ++i) {
                const int xa = 2 * i, xb = std::min(2 * i + 1, w_ - 1);
                Range r = Range::of(da[xa], ma[xa]);
                r.add(Range::of(da[xb], ma[xb]));
                r.add(Range::of(db[xa], mb[xa]));
                r.add(Range::of(db[xb], mb[xb]));
                base_.set(k + i, r);
            }
        }
    }

    // Levels 1 and up of the starting cell at x0_; blocks past the image's right edge repeat the
    // last column of blocks.
    void fill_upper() {
        for (int level = 1; level < kLevels && side_[level] > 0; ++level)
            for (int j = 0; j < side_[level]; ++j)
                for (int i = 0; i < side_[level]; ++i) {
                    Range r = at(level - 1, 2 * i, 2 * j);
                    r.add(at(level - 1, 2 * i + 1, 2 * j));
                    r.add(at(level - 1, 2 * i, 2 * j + 1));
                    r.add(at(level - 1, 2 * i + 1, 2 * j + 1));
                    upper_.set(offset_[level] + j * side_[level] + i, r);
                }
    }

    Range at(int level, int i, int j) const {
        if (level > 0) return upper_.get(offset_[level] + j * side_[level] + i);
        return base_.get(j * base_blocks_ + std::min(x0_ / 2 + i, base_blocks_ - 1));
    }

    void subdivide(int x, int y, int s, int level) {
        if (x >= w_ || y >= h_) return;
        const Range r = s == 1 ? Range::of(depth_(x, y), motion_(x, y))
                               : at(level, (x - x0_) / s, (y - y0_) / s);
        if (s > p_.min_cell && r.discontinuous(p_)) {
            const int half = s / 2;
            subdivide(x, y, half, level - 1);
            subdivide(x + half, y, half, level - 1);
            subdivide(x, y + half, half, level - 1);
            subdivide(x + half, y + half, half, level - 1);
        } else if (!r.invalid()) {
            emit(x, y, std::min(x + s, w_), std::min(y + s, h_));
        }
    }

    // Vertex at grid point (cx, cy) moved by depth z and motion m; false when it lands too far.
    bool place(int cx, int cy, float z, float mx, float my, Vertex& v) const {
        const float tx = float(cx) + p_.factor * mx, ty = float(cy) + p_.factor * my;
        if (!(std::fabs(tx) <= kMaxCoordinate && std::fabs(ty) <= kMaxCoordinate)) return false;
        v = {to_fixed(tx), to_fixed(ty), float(cx), float(cy), z, mx, my};
        return true;
    }

    // The vertex at grid point (cx, cy) takes the mean depth and motion of the 2x2 pixels around
    // it where they are continuous (the same for every cell that shares it, so remembered for
    // the current starting cell), else those of (ix, iy), the cell's pixel nearest to it.
    bool vertex(int cx, int cy, int ix, int iy, Vertex& v) {
        const int mc = p_.min_cell;
        const int k = ((cy - y0_ + mc - 1) / mc) * lattice_ + (cx - x0_ + mc - 1) / mc;
        uint8_t& state = state_[k];
        if (state == kUnknown) {
            const int xa = std::max(cx - 1, 0), xb = std::min(cx, w_ - 1);
            const int ya = std::max(cy - 1, 0), yb = std::min(cy, h_ - 1);
            const float d[4] = {depth_(xa, ya), depth_(xb, ya), depth_(xa, yb), depth_(xb, yb)};
            const glm::vec2 m[4] = {motion_(xa, ya), motion_(xb, ya), motion_(xa, yb),
                                    motion_(xb, yb)};
            Range r = Range::of(d[0], m[0]);
            for (int i = 1; i < 4; ++i) r.add(Range::of(d[i], m[i]));
            if (r.discontinuous(p_)) {
                state = kTorn;
            } else {
                const float z = r.zmin < kBackgroundFrom ? ((d[0] + d[1]) + (d[2] + d[3])) * 0.25f
                                                         : kBackgroundDepth;
                const glm::vec2 mean = ((m[0] + m[1]) + (m[2] + m[3])) * 0.25f;
                state = place(cx, cy, z, mean.x, mean.y, shared_[k]) ? kShared : kFar;
            }
        }
        if (state == kShared) {
            v = shared_[k];
            return true;
        }
        if (state == kFar) return false;
        const float d = depth_(ix, iy);
        const glm::vec2 m = motion_(ix, iy);
        return place(cx, cy, d < kBackgroundFrom ? d : kBackgroundDepth, m.x, m.y, v);
    }

    void emit(int x, int y, int x1, int y1) {
        Cell c;
        if (!vertex(x, y, x, y, c.v[0]) || !vertex(x1, y, x1 - 1, y, c.v[1]) ||
            !vertex(x1, y1, x1 - 1, y1 - 1, c.v[2]) || !vertex(x, y1, x, y1 - 1, c.v[3]))
            return;
        int lo = c.v[0].y, hi = c.v[0].y;
        for (const Vertex& v : c.v) {
            lo = std::min(lo, v.y);
            hi = std::max(hi, v.y);
        }
        row_->y_lo = std::min(row_->y_lo, first_centre(int64_t(lo) - kOverlap));
        row_->y_hi = std::max(row_->y_hi, last_centre(int64_t(hi) + kOverlap));
        row_->cells.push_back(c);
    }

    static constexpr int kLevels = 6;  // block sizes 2..64
    enum : uint8_t { kUnknown, kShared, kFar, kTorn };
    static constexpr int kUpper = 16 * 16 + 8 * 8 + 4 * 4 + 2 * 2 + 1;

    ImageView<const float> depth_;
    ImageView<const glm::vec2> motion_;
    int w_, h_;
    Params p_;
    bool simd_;
    int base_blocks_;  // level-0 blocks to a row
    Ranges base_{}, upper_{};
    float zmin_[kUpper], zmax_[kUpper];
    glm::vec2 m0_[kUpper], m1_[kUpper];
    int offset_[kLevels] = {};
    int side_[kLevels] = {};
    int lattice_ = 0;  // grid points to a row of the starting cell
    uint8_t* state_ = nullptr;
    Vertex* shared_ = nullptr;
    int x0_ = 0, y0_ = 0;
    Row* row_ = nullptr;
};

}  // namespace

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

void build_rows(const Frame& source, const Params& params, int begin, int end, bool simd,
                Scratch& scratch, Row* rows) {
    Builder builder(source, params, simd, scratch);
    for (int r = begin; r < end; ++r) builder.build_row(r, rows[r]);
}

}  // namespace reprise::warp::grid
