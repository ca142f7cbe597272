// Growing the adaptive grid: each starting cell is split in four while its pixels depart from
// what its corner pixels predict (or it holds invalid pixels, or background beside geometry),
// and its leaves get vertices moved along the motion.
#include <algorithm>
#include <cmath>
#include <vector>

#include "grid_internal.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace reprise::warp::grid {

namespace {

constexpr float kMaxCoordinate = 1048576.0f;  // 2^20 px; further vertices drop their cell

bool valid_motion(glm::vec2 m) {
    return std::fabs(m.x) < kHugeMotion && std::fabs(m.y) < kHugeMotion;
}

// Depth and motion ranges of a few pixels (a smallest cell, the 2x2 around a grid point).
// Invalid depth (NaN, negative) enters as -1 and invalid motion as kInvalidMotion, so the
// ranges alone tell whether the block holds any.
struct Range {
    static constexpr float kInvalidMotion = 1e38f;
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
    bool mixed() const { return zmin < kBackgroundFrom && zmax >= kBackgroundFrom; }
    // Valid, one kind, depth ratio and motion range within bounds.
    bool narrow(float z_ratio, float motion) const {
        return !invalid() && !mixed() && (zmin >= kBackgroundFrom || zmax <= zmin * z_ratio) &&
               m1.x - m0.x <= motion && m1.y - m0.y <= motion;
    }
};

// The smoothness test of one row of a cell: pixels [begin, n) of the row, at u = i * iu,
// against the prediction a + u * b of the triangle they lie in (the upper-right one, index 0,
// where u >= v). A pixel fails when its depth is not of the cell's kind (geometry:
// |1 - predicted(1/z) * z| > depth_tolerance, which also fails NaN, negative, zero and
// background depths; background: depth below kBackgroundFrom or NaN), when its motion is
// invalid, or when it departs from the predicted motion by more than motion_limit on either
// axis. NaN fails everywhere.
bool row_fits_scalar(const RowFit& f, const float* z, const glm::vec2* m, int begin, int n) {
    for (int i = begin; i < n; ++i) {
        const float u = float(i) * f.iu;
        const int t = u >= f.v ? 0 : 1;
        if (f.background) {
            if (!(z[i] >= kBackgroundFrom)) return false;
        } else {
            const float w = f.wa[t] + u * f.wb[t];
            if (!(std::fabs(1.0f - w * z[i]) <= f.depth_tolerance)) return false;
        }
        const float px = f.ma[t].x + u * f.mb[t].x, py = f.ma[t].y + u * f.mb[t].y;
        if (!(std::fabs(m[i].x - px) <= f.motion_limit && std::fabs(m[i].x) < kHugeMotion &&
              std::fabs(m[i].y - py) <= f.motion_limit && std::fabs(m[i].y) < kHugeMotion))
            return false;
    }
    return true;
}

#if defined(__SSE2__)
// The same, four pixels a step; the pixels past the last whole step go to the scalar loop.
bool row_fits_sse2(const RowFit& f, const float* z, const glm::vec2* m, int n) {
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 lanes = _mm_setr_ps(0.0f, 1.0f, 2.0f, 3.0f), iu = _mm_set1_ps(f.iu);
    const __m128 v = _mm_set1_ps(f.v), one = _mm_set1_ps(1.0f);
    const __m128 tz = _mm_set1_ps(f.depth_tolerance), tm = _mm_set1_ps(f.motion_limit);
    const __m128 background = _mm_set1_ps(kBackgroundFrom), huge = _mm_set1_ps(kHugeMotion);
    const __m128 wa0 = _mm_set1_ps(f.wa[0]), wa1 = _mm_set1_ps(f.wa[1]);
    const __m128 wb0 = _mm_set1_ps(f.wb[0]), wb1 = _mm_set1_ps(f.wb[1]);
    const __m128 ma0 = _mm_setr_ps(f.ma[0].x, f.ma[0].y, f.ma[0].x, f.ma[0].y);
    const __m128 ma1 = _mm_setr_ps(f.ma[1].x, f.ma[1].y, f.ma[1].x, f.ma[1].y);
    const __m128 mb0 = _mm_setr_ps(f.mb[0].x, f.mb[0].y, f.mb[0].x, f.mb[0].y);
    const __m128 mb1 = _mm_setr_ps(f.mb[1].x, f.mb[1].y, f.mb[1].x, f.mb[1].y);
    auto select = [](__m128 first, __m128 a, __m128 b) {
        return _mm_or_ps(_mm_and_ps(first, a), _mm_andnot_ps(first, b));
    };
    // Four pixels whose prediction coefficients are (wa, wb) and (ma, mb) lane by lane.
    auto fits4 = [&](__m128 u, __m128 wa, __m128 wb, __m128 ma01, __m128 mb01, __m128 ma23,
                     __m128 mb23, const float* zp, const glm::vec2* mp) {
        const __m128 zz = _mm_loadu_ps(zp);
        __m128 ok;
        if (f.background) {
            ok = _mm_cmpge_ps(zz, background);
        } else {
            const __m128 w = _mm_add_ps(wa, _mm_mul_ps(u, wb));
            ok = _mm_cmple_ps(_mm_and_ps(_mm_sub_ps(one, _mm_mul_ps(w, zz)), abs_mask), tz);
        }
        auto motion_ok = [&](__m128 uu, __m128 ma, __m128 mb, const glm::vec2* p) {
            const __m128 mm = _mm_loadu_ps(&p->x);
            const __m128 predicted = _mm_add_ps(ma, _mm_mul_ps(uu, mb));
            return _mm_and_ps(_mm_cmple_ps(_mm_and_ps(_mm_sub_ps(mm, predicted), abs_mask), tm),
                              _mm_cmplt_ps(_mm_and_ps(mm, abs_mask), huge));
        };
        const __m128 ok01 = motion_ok(_mm_unpacklo_ps(u, u), ma01, mb01, mp);
        const __m128 ok23 = motion_ok(_mm_unpackhi_ps(u, u), ma23, mb23, mp + 2);
        // Lane k of `ok` is pixel k: both axes of it must pass.
        const __m128 x = _mm_shuffle_ps(ok01, ok23, _MM_SHUFFLE(2, 0, 2, 0));
        const __m128 y = _mm_shuffle_ps(ok01, ok23, _MM_SHUFFLE(3, 1, 3, 1));
        return _mm_movemask_ps(_mm_and_ps(ok, _mm_and_ps(x, y))) == 0xf;
    };
    int i = 0;
    for (; i + 4 <= n; i += 4) {
        const __m128 u = _mm_mul_ps(_mm_add_ps(_mm_set1_ps(float(i)), lanes), iu);
        const __m128 upper = _mm_cmpge_ps(u, v);
        const int sides = _mm_movemask_ps(upper);
        bool ok;
        if (sides == 0xf) {  // all four in the upper triangle
            ok = fits4(u, wa0, wb0, ma0, mb0, ma0, mb0, z + i, m + i);
        } else if (sides == 0) {
            ok = fits4(u, wa1, wb1, ma1, mb1, ma1, mb1, z + i, m + i);
        } else {
            const __m128 up01 = _mm_unpacklo_ps(upper, upper), up23 = _mm_unpackhi_ps(upper, upper);
            ok = fits4(u, select(upper, wa0, wa1), select(upper, wb0, wb1), select(up01, ma0, ma1),
                       select(up01, mb0, mb1), select(up23, ma0, ma1), select(up23, mb0, mb1),
                       z + i, m + i);
        }
        if (!ok) return false;
    }
    return row_fits_scalar(f, z, m, i, n);
}
#endif

// A float to fixed point, rounded to nearest (ties up); |v| <= 2^20.
int32_t to_fixed(float v) {
    const double scaled = double(v) * kSubpixel + 0.5;
    int64_t i = int64_t(scaled);
    if (double(i) > scaled) --i;
    return int32_t(i);
}

// Grows the cells of one row of starting cells.
class Builder {
public:
    Builder(const GBufferView& source, const Params& params, bool simd, Scratch& scratch)
        : depth_(source.depth),
          motion_(source.motion),
          w_(source.width()),
          h_(source.height()),
          p_(params),
          simd_(simd) {
        const std::size_t count = std::size_t((w_ + p_.cell - 1) / p_.cell);
        if (scratch.fits.size() < count) {
            scratch.fits.resize(count);
            scratch.fitting.resize(count);
        }
        fits_ = scratch.fits.data();
        ok_ = scratch.fitting.data();
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
        const int y1 = std::min(y0_ + p_.cell, h_);
        // The starting cells of the row are tested together, image row by image row, so that
        // the frame is read in order; those that fail are split.
        const int count = (w_ + p_.cell - 1) / p_.cell;
        if (p_.cell > p_.min_cell) {
            for (int i = 0; i < count; ++i) {
                const int x = i * p_.cell;
                ok_[i] = start(x, y0_, std::min(x + p_.cell, w_), y1, fits_[i]);
            }
            for (int j = 0; j < y1 - y0_; ++j)
                for (int i = 0; i < count; ++i)
                    if (ok_[i]) ok_[i] = fit_row(fits_[i], j);
        }
        for (int i = 0; i < count; ++i) {
            x0_ = i * p_.cell;
            std::fill_n(state_, lattice_ * lattice_, kUnknown);
            if (p_.cell > p_.min_cell && ok_[i])
                emit(x0_, y0_, std::min(x0_ + p_.cell, w_), y1, true);
            else
                subdivide(x0_, y0_, p_.cell, true);
        }
    }

private:
    // `failed`: the block is known not to fit.
    void subdivide(int x, int y, int s, bool failed = false) {
        if (x >= w_ || y >= h_) return;
        const int x1 = std::min(x + s, w_), y1 = std::min(y + s, h_);
        if (s > p_.min_cell) {
            if (!failed && fits(x, y, x1, y1)) {
                emit(x, y, x1, y1, true);
            } else {
                const int half = s / 2;
                subdivide(x, y, half);
                subdivide(x + half, y, half);
                subdivide(x, y + half, half);
                subdivide(x + half, y + half, half);
            }
            return;
        }
        // A smallest cell: drawn unless it holds invalid pixels, and smooth by the test of the
        // pixels around a shared vertex (its pixels are its corners).
        Range r = Range::of(depth_(x, y), motion_(x, y));
        for (int j = y; j < y1; ++j)
            for (int i = x; i < x1; ++i) r.add(Range::of(depth_(i, j), motion_(i, j)));
        if (!r.invalid()) emit(x, y, x1, y1, r.narrow(p_.vertex_z_ratio, p_.vertex_motion));
    }

    // The smoothness test of a block: whether every pixel of [x, x1) x [y, y1) is valid, of the
    // kind of its corners (all geometry or all background) and within the thresholds of the
    // interpolation of its corner pixels over the two triangles of the cell. Set up by
    // `start` (false when a corner already fails), then run row by row.
    bool start(int x, int y, int x1, int y1, CellFit& fit) const {
        const int n = x1 - x, rows = y1 - y;
        // Two pixels wide or high (a border strip, a smallest block): each column or row is
        // predicted from its own ends, so an edge between the two would pass; one surface only.
        if (n <= 2 || rows <= 2) {
            Range r = Range::of(depth_(x, y), motion_(x, y));
            for (int j = y; j < y1; ++j)
                for (int i = x; i < x1; ++i) r.add(Range::of(depth_(i, j), motion_(i, j)));
            if (!r.narrow(p_.vertex_z_ratio, p_.vertex_motion)) return false;
        }
        const int xr = x1 - 1, yb = y1 - 1;
        // Corners top-left, top-right, bottom-right, bottom-left.
        const float z[4] = {depth_(x, y), depth_(xr, y), depth_(xr, yb), depth_(x, yb)};
        const glm::vec2 m[4] = {motion_(x, y), motion_(xr, y), motion_(xr, yb), motion_(x, yb)};
        int background = 0;
        for (int k = 0; k < 4; ++k) {
            if (!(z[k] >= 0.0f) || !valid_motion(m[k])) return false;
            background += z[k] >= kBackgroundFrom;
        }
        if (background != 0 && background != 4) return false;
        RowFit& f = fit.f;
        f = {};
        f.background = background == 4;
        f.depth_tolerance = p_.depth_tolerance;
        f.motion_limit = p_.motion_limit;
        f.iu = n > 1 ? 1.0f / float(n - 1) : 0.0f;
        fit.iv = rows > 1 ? 1.0f / float(rows - 1) : 0.0f;
        fit.x = x;
        fit.y = y;
        fit.n = n;
        float w[4];
        for (int k = 0; k < 4; ++k) w[k] = f.background ? 0.0f : 1.0f / z[k];
        // Upper triangle (top-left, top-right, bottom-right): c0 + u (c1 - c0) + v (c2 - c1);
        // lower (top-left, bottom-right, bottom-left): c0 + u (c2 - c3) + v (c3 - c0).
        f.wb[0] = w[1] - w[0];
        f.wb[1] = w[2] - w[3];
        f.mb[0] = m[1] - m[0];
        f.mb[1] = m[2] - m[3];
        fit.w0 = w[0];
        fit.wv[0] = w[2] - w[1];
        fit.wv[1] = w[3] - w[0];
        fit.m0 = m[0];
        fit.mv[0] = m[2] - m[1];
        fit.mv[1] = m[3] - m[0];
        return true;
    }

    // Row j of the block.
    bool fit_row(CellFit& fit, int j) const {
        RowFit& f = fit.f;
        f.v = float(j) * fit.iv;
        for (int t = 0; t < 2; ++t) {
            f.wa[t] = fit.w0 + f.v * fit.wv[t];
            f.ma[t] = {fit.m0.x + f.v * fit.mv[t].x, fit.m0.y + f.v * fit.mv[t].y};
        }
        const float* z = depth_.row(fit.y + j) + fit.x;
        const glm::vec2* m = motion_.row(fit.y + j) + fit.x;
#if defined(__SSE2__)
        if (simd_) return row_fits_sse2(f, z, m, fit.n);
#endif
        return row_fits_scalar(f, z, m, 0, fit.n);
    }

    bool fits(int x, int y, int x1, int y1) const {
        CellFit fit;
        if (!start(x, y, x1, y1, fit)) return false;
        for (int j = 0; j < y1 - y; ++j)
            if (!fit_row(fit, j)) return false;
        return true;
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
            if (!r.narrow(p_.vertex_z_ratio, p_.vertex_motion)) {
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

    // An edge triangle across a depth edge whose area grew by more than stretched_area from the
    // source to the target spans what the source did not see.
    uint8_t coverage(const Vertex& a, const Vertex& b, const Vertex& c) const {
        const float z_lo = std::min({a.z, b.z, c.z}), z_hi = std::max({a.z, b.z, c.z});
        if (!(z_hi > z_lo * p_.vertex_z_ratio)) return 1;
        const double source =
            std::fabs(double(b.sx - a.sx) * (c.sy - a.sy) - double(b.sy - a.sy) * (c.sx - a.sx));
        const double target = std::fabs(double(int64_t(b.x) - a.x) * (int64_t(c.y) - a.y) -
                                        double(int64_t(b.y) - a.y) * (int64_t(c.x) - a.x)) /
                              (double(kSubpixel) * kSubpixel);
        return (target - source) * 0.5 > p_.stretched_area ? kCoveredStretched : 1;
    }

    void emit(int x, int y, int x1, int y1, bool smooth) {
        Cell c;
        c.perspective = smooth;
        if (!vertex(x, y, x, y, c.v[0]) || !vertex(x1, y, x1 - 1, y, c.v[1]) ||
            !vertex(x1, y1, x1 - 1, y1 - 1, c.v[2]) || !vertex(x, y1, x, y1 - 1, c.v[3]))
            return;
        c.coverage[0] = smooth ? 1 : coverage(c.v[0], c.v[1], c.v[2]);
        c.coverage[1] = smooth ? 1 : coverage(c.v[0], c.v[2], c.v[3]);
        int lo = c.v[0].y, hi = c.v[0].y;
        for (const Vertex& v : c.v) {
            lo = std::min(lo, v.y);
            hi = std::max(hi, v.y);
        }
        row_->y_lo = std::min(row_->y_lo, first_centre(int64_t(lo) - kOverlap));
        row_->y_hi = std::max(row_->y_hi, last_centre(int64_t(hi) + kOverlap));
        row_->cells.push_back(c);
    }

    enum : uint8_t { kUnknown, kShared, kFar, kTorn };

    ImageView<const float> depth_;
    ImageView<const glm::vec2> motion_;
    int w_, h_;
    Params p_;
    bool simd_;
    CellFit* fits_ = nullptr;  // the tests of a row of starting cells
    uint8_t* ok_ = nullptr;    // which of them still pass
    int lattice_ = 0;          // grid points to a row of the starting cell
    uint8_t* state_ = nullptr;
    Vertex* shared_ = nullptr;
    int x0_ = 0, y0_ = 0;
    Row* row_ = nullptr;
};

}  // namespace

}  // namespace reprise::warp::grid

namespace reprise::warp {

GridParameters grid_parameters(const GridOptions& o, float factor) {
    REPRISE_ASSERT(std::isfinite(factor));
    GridParameters p{};
    p.min_cell = std::clamp(o.min_cell, 1, 2);
    p.cell = p.min_cell;
    while (p.cell * 2 <= std::min(o.cell, grid::kMaxCell)) p.cell *= 2;
    // NaN thresholds count as 0; the relative depth tolerance stays below 1 so that zero and
    // negative depths always fail it.
    p.depth_tolerance = o.depth_threshold > 0.0f ? std::min(o.depth_threshold, 0.5f) : 0.0f;
    const float motion = o.motion_threshold > 0.0f ? o.motion_threshold : 0.0f;
    p.motion_limit = factor != 0.0f ? motion / std::fabs(factor) : grid::kInf;
    p.vertex_z_ratio = 1.0f + 2.0f * p.depth_tolerance;
    p.vertex_motion = 2.0f * p.motion_limit;
    p.stretched_area = o.stretched_area >= 0.0f ? o.stretched_area : 0.0f;  // NaN: 0
    p.factor = factor;
    return p;
}

}  // namespace reprise::warp

namespace reprise::warp::grid {

void size_scratch(Scratch& scratch, const Params& params, int source_width, int target_width,
                  int band_rows, bool motion) {
    const std::size_t count = std::size_t((source_width + params.cell - 1) / params.cell);
    if (scratch.fits.size() < count) {
        scratch.fits.resize(count);
        scratch.fitting.resize(count);
    }
    const std::size_t lattice = std::size_t(params.cell / params.min_cell + 1);
    if (scratch.point_state.size() < lattice * lattice) {
        scratch.point_state.resize(lattice * lattice);
        scratch.points.resize(lattice * lattice);
    }
    scratch_rows(scratch.color, target_width, band_rows);
    scratch_rows(scratch.depth, target_width, band_rows);
    scratch_rows(scratch.covered, target_width, band_rows);
    if (motion) scratch_rows(scratch.motion, target_width, band_rows);
}

void build_rows(const GBufferView& source, const Params& params, int begin, int end, bool simd,
                Scratch& scratch, Row* rows) {
    Builder builder(source, params, simd, scratch);
    for (int r = begin; r < end; ++r) builder.build_row(r, rows[r]);
}

}  // namespace reprise::warp::grid
