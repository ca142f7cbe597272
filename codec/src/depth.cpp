// Depth: each pixel as a 32-bit code (the float's bits in an order-preserving map, the
// quantised log2 depth, or 1/z in 32nds of the view step), predicted per 8x8 block from the
// reference depth forward-projected into this camera, spatially (median edge detector) or, in
// view mode, by a plane the block sends (offset and slopes); residuals context-coded (by edges,
// and by what the reprojection shows). A pixel the block's prediction misses may take another
// one for a flag (inter frames: the other of temporal and spatial, then in view mode the
// neighbour's temporal code across an edge; view-mode key frames: the neighbour across an edge).
// Blocks predicted exactly cost two flags. View mode sends the
// prediction itself wherever it is within the bound and quantises residuals, so decoded depth
// keeps its error from frame to frame instead of being rounded again each time.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "internal.hpp"
#include "kernels.hpp"
#include "least_squares.hpp"
#include "slices.hpp"

namespace reprise::codec {

namespace {

constexpr int kBlock = 8;
constexpr uint8_t kAllPredicted = 1;
constexpr uint8_t kOwnStep = 2;  // view depth: this frame's 1/z step follows (f32)
constexpr float kMinViewStep = 1e-12f, kMaxViewStep = 1e6f;

// View-mode codes are k = round(1/z / (q / 32)) in 0..2^30 (k = 0 decodes as half a code), for
// the view step q; residuals count steps of 33 codes, so the nearest choice errs by at most q / 2.
constexpr int kViewResidualStep = kViewCodesPerStep + 1;

struct Mapping {
    bool lossless;
    bool view;                   // uniform in 1/z
    double step;                 // log2 step (bounded) or 1/z per code (view: q / 32)
    double displacement = 0.0;   // view: the declared largest camera displacement (encoder only)
    uint32_t residual_step = 1;  // codes per residual unit

    uint32_t code(float z) const {
        if (lossless) {
            uint32_t u;
            std::memcpy(&u, &z, 4);
            const uint32_t o = (u & 0x80000000u) ? ~u : (u | 0x80000000u);
            return o == kNoPrediction ? o - 1 : o;  // -NaN with all payload bits: one step off
        }
        if (z == std::numeric_limits<float>::infinity()) return kInfCode;
        if (!(z > 0.0f) || !std::isfinite(z)) return kInvalidCode;
        if (view)
            return uint32_t(std::min(std::nearbyint(1.0 / double(z) / step), double(kMaxViewCode)));
        const double k = std::nearbyint(exact_log2(double(z)) / step);
        return uint32_t(int32_t(std::clamp(k, -double(1 << 30), double(1 << 30))));
    }
    // The inverse depth a view-mode code decodes to.
    double inverse_depth(uint32_t c) const { return c == 0 ? 0.5 * step : double(c) * step; }
    float depth(uint32_t c) const {
        if (lossless) {
            const uint32_t u = (c & 0x80000000u) ? (c & 0x7FFFFFFFu) : ~c;
            float z;
            std::memcpy(&z, &u, 4);
            return z;
        }
        if (c == kInfCode) return std::numeric_limits<float>::infinity();
        if (view)
            return c > kMaxViewCode ? std::numeric_limits<float>::quiet_NaN()
                                    : float(1.0 / inverse_depth(c));
        const int32_t k = int32_t(c);
        if (k > (1 << 30) || k < -(1 << 30)) return std::numeric_limits<float>::quiet_NaN();
        return float(exact_exp2(double(k) * step));
    }
    uint32_t empty() const {
        return lossless ? code(std::numeric_limits<float>::infinity()) : kInfCode;
    }
    // A code of a surface: finite positive depth (not background, not invalid).
    bool surface(uint32_t c) const {
        if (lossless) {
            const float z = depth(c);
            return z > 0.0f && z < std::numeric_limits<float>::infinity();
        }
        return c != kInfCode && c != kInvalidCode && c != kNoPrediction &&
               (!view || c <= kMaxViewCode);
    }
};

// View mode: code c (at most 2^30) decodes to an inverse depth within the bound of w (docs/
// bitstream.md): the allowance shrinks by (1 - B max(w, w_c))^2 for points near the camera.
// `share` < 1 asks for that share of the allowance.
inline bool view_code_within(double w, uint32_t c, double step, double displacement,
                             double share = 1.0) {
    const double wc = c == 0 ? 0.5 * step : double(c) * step;
    const double near = std::max(0.0, 1.0 - displacement * std::max(w, wc));
    return std::abs(wc - w) <= share * kViewCodesPerStep * step * near * near;
}

Mapping mapping_of(const SequenceParams& sp, float view_step) {
    const bool view = sp.depth == DepthMode::View;
    return {sp.depth == DepthMode::Lossless, view,
            view ? double(view_step) / kViewCodesPerStep : sp.depth_step(),
            double(sp.view_displacement), view ? uint32_t(kViewResidualStep) : 1u};
}

inline uint32_t median_edge(int64_t a, int64_t b, int64_t c) {
    if (c >= std::max(a, b)) return uint32_t(std::min(a, b));
    if (c <= std::min(a, b)) return uint32_t(std::max(a, b));
    return uint32_t(a + b - c);
}

inline int magnitude_class(uint32_t left, uint32_t top) {
    auto mag = [](uint32_t r) { return uint64_t(std::abs(int64_t(int32_t(r)))); };
    const uint64_t s = mag(left) + mag(top);
    return s == 0 ? 0 : s <= 8 ? 1 : s <= 256 ? 2 : 3;
}

// Two codes further apart than one residual step: an edge, where residuals gather.
inline bool step_between(const Mapping& map, uint32_t a, uint32_t b) {
    return std::abs(int64_t(a) - int64_t(b)) > int64_t(map.residual_step);
}

// Block flags: bit 0 temporal, bit 1 zero (no residuals), bit 2 plane (view mode).
constexpr uint8_t kTemporalBlock = 1, kZeroBlock = 2, kPlaneBlock = 4;

// A plane block's prediction (view mode): codes c at the block's centre, gx and gy codes per
// pixel; the offset is sent in steps of kPlaneOffsetStep codes. The limits keep every sum in
// 64 bits whatever a stream says; no plane of real codes comes near them.
struct Plane {
    int64_t c = 0, gx = 0, gy = 0;
};
constexpr int64_t kPlaneOffsetStep = 16;
constexpr uint64_t kZeroFlags = 24;  // encoder: the estimated bits of a block's 64 zero flags
constexpr int64_t kMaxPlaneOffset = int64_t(1) << 32, kMaxPlaneSlope = int64_t(1) << 30;

inline bool plane_in_range(const Plane& q) {
    return std::abs(q.c) <= kMaxPlaneOffset && std::abs(q.gx) <= kMaxPlaneSlope &&
           std::abs(q.gy) <= kMaxPlaneSlope;
}

inline uint32_t plane_code(const Plane& q, int dx, int dy) {
    const int64_t v = q.c + ((q.gx * (2 * dx - 7) + q.gy * (2 * dy - 7)) >> 1);
    return uint32_t(std::clamp<int64_t>(v, 0, kMaxViewCode));
}

struct Models {
    BitModel temporal[3][3];
    BitModel plane[3][3];  // [what the block shows][neighbours]
    BitModel zero_block[3][3][3][2];
    BitModel background[32];  // version 17 (4 before)
    IntModel<24> residual[2][48];
    BitModel other[2][3];
    IntModel<24> other_residual[2];  // version 17: a residual from the other prediction
    BitModel across[2][3];           // version 14
    IntModel<24> plane_offset[2], plane_slope[2][2];
};

// The pieces one slice needs; codes (V) and residuals (R) are full-frame images.
struct SliceJob {
    const Mapping* map;
    int width, y0, y1;
    ImageView<uint32_t> codes;  // decoder fills; encoder has them, or chooses them in view mode
    ImageView<const uint32_t> temporal;  // kNoPrediction where nothing landed; empty on key frames
    ImageView<uint32_t> residuals;
    ImageView<uint32_t> predictions;  // encoder: the block's prediction of each pixel
    ImageView<const float> source;    // encoder, view mode: the depth to code
    ImageView<const float> share;     // encoder, view mode: each pixel's multiple of the bound
    float uniform_share = 1.0f;       // encoder, view mode: every pixel's, where `share` is empty
    ImageView<const uint8_t> shows;   // inter frames: each block's reprojection_class (block_shows)
    std::size_t zero_blocks = 0;
    std::size_t plane_blocks = 0;
    StreamStats::DepthBits bits;  // encoder: where the slice's bits go
    Plane plane;                  // the plane of the block being predicted
    int plane_x = 0, plane_y = 0;
};

// Lossless depth is predicted in inverse depth, which is affine across a plane in screen space:
// the median edge detector there predicts planes to within a few units in the last place.
inline uint32_t inverse_depth_median(const Mapping& map, uint32_t ca, uint32_t cb, uint32_t cc) {
    const float a = map.depth(ca), b = map.depth(cb), c = map.depth(cc);
    if (!(a > 0.0f && b > 0.0f && c > 0.0f && a < INFINITY && b < INFINITY && c < INFINITY))
        return median_edge(ca, cb, cc);
    const float ia = 1.0f / a, ib = 1.0f / b, ic = 1.0f / c;
    float p;
    if (ic >= std::max(ia, ib))
        p = std::min(ia, ib);
    else if (ic <= std::min(ia, ib))
        p = std::max(ia, ib);
    else
        p = ia + ib - ic;
    return map.code(1.0f / p);
}

inline uint32_t spatial(const SliceJob& j, int x, int y) {
    const bool left = x > 0, top = y > j.y0;
    if (left && top) {
        if (j.map->lossless)
            return inverse_depth_median(*j.map, j.codes(x - 1, y), j.codes(x, y - 1),
                                        j.codes(x - 1, y - 1));
        return median_edge(j.codes(x - 1, y), j.codes(x, y - 1), j.codes(x - 1, y - 1));
    }
    if (left) return j.codes(x - 1, y);
    if (top) return j.codes(x, y - 1);
    return j.map->empty();
}

inline uint32_t predict(const SliceJob& j, int x, int y, bool temporal) {
    if (temporal) {
        const uint32_t t = j.temporal(x, y);
        if (t != kNoPrediction) return t;
    }
    return spatial(j, x, y);
}

// How a block is predicted: spatially, from the reprojected reference, or by a plane it sends.
enum BlockMode { kSpatialMode = 0, kTemporalMode = 1, kPlaneMode = 2 };

inline uint32_t block_prediction(const SliceJob& j, int x, int y, int mode) {
    return mode == kPlaneMode ? plane_code(j.plane, x - j.plane_x, y - j.plane_y)
                              : predict(j, x, y, mode == kTemporalMode);
}

// A plane block's parameters are predicted from the plane blocks to its left and above (the
// surface continued), else from the two rows above the block: the surface at the pixel above its
// middle, or the nearest surface pixel to that in the row above, continued with its slopes.
Plane predicted_plane(const SliceJob& j, int b, int by, const std::vector<uint8_t>& row,
                      const std::vector<uint8_t>& above, const std::vector<Plane>& planes,
                      const std::vector<Plane>& above_planes) {
    const bool left = b > 0 && (row[b - 1] & kPlaneBlock);
    const bool up = !above.empty() && (above[b] & kPlaneBlock);
    if (left && up) {
        const Plane &l = planes[b - 1], &a = above_planes[b];
        return {(l.c + kBlock * l.gx + a.c + kBlock * a.gy) >> 1, (l.gx + a.gx) >> 1,
                (l.gy + a.gy) >> 1};
    }
    if (left)
        return {planes[b - 1].c + kBlock * planes[b - 1].gx, planes[b - 1].gx, planes[b - 1].gy};
    if (up)
        return {above_planes[b].c + kBlock * above_planes[b].gy, above_planes[b].gx,
                above_planes[b].gy};
    for (const int d : {-1, 1}) {  // above-left, then above-right
        const int n = b + d;
        if (above.empty() || n < 0 || n >= int(above.size()) || !(above[n] & kPlaneBlock)) continue;
        const Plane& a = above_planes[std::size_t(n)];
        return {a.c - d * kBlock * a.gx + kBlock * a.gy, a.gx, a.gy};
    }
    if (by == j.y0) return {};
    const int x0 = b * kBlock, mid = std::min(x0 + kBlock / 2, j.width - 1);
    int at = -1;
    for (int d = 0; d < kBlock && at < 0; ++d)
        for (const int x : {mid - d, mid + d})
            if (at < 0 && x >= 0 && x < j.width && j.codes(x, by - 1) <= kMaxViewCode) at = x;
    if (at < 0) return {};
    const int64_t m = j.codes(at, by - 1);
    auto same = [&](int x, int y) {  // a code of the same surface
        return x >= 0 && x < j.width && y >= j.y0 && j.codes(x, y) <= kMaxViewCode &&
               !step_between(*j.map, j.codes(x, y), uint32_t(m));
    };
    Plane q{m, 0, 0};
    if (same(at - 1, by - 1) && same(at + 1, by - 1))
        q.gx = (int64_t(j.codes(at + 1, by - 1)) - int64_t(j.codes(at - 1, by - 1))) >> 1;
    else if (same(at + 1, by - 1))
        q.gx = int64_t(j.codes(at + 1, by - 1)) - m;
    else if (same(at - 1, by - 1))
        q.gx = m - int64_t(j.codes(at - 1, by - 1));
    if (same(at, by - 2)) q.gy = m - int64_t(j.codes(at, by - 2));
    q.c = m + ((q.gx * (2 * (x0 - at) + 7) + q.gy * 9) >> 1);  // at the block's centre
    return plane_in_range(q) ? q : Plane{m, 0, 0};
}

inline int plane_context(const std::vector<uint8_t>& row, const std::vector<uint8_t>& above,
                         int b) {
    const int n =
        (b > 0 && (row[b - 1] & kPlaneBlock)) + (!above.empty() && (above[b] & kPlaneBlock));
    if (n > 0 || above.empty()) return n;
    return (b > 0 && (above[b - 1] & kPlaneBlock)) ||
           (b + 1 < int(above.size()) && (above[b + 1] & kPlaneBlock));
}

// Whether (x + 1, y - 1) is a code the encoder, which decides block by block, already knows when
// it predicts (x, y): in the band above or in the same 8-pixel block.
inline bool above_right_known(const SliceJob& j, int x, int y) {
    return y > j.y0 && x + 1 < j.width && ((x + 1) % kBlock != 0 || (y - j.y0) % kBlock == 0);
}

// In a block with residuals, a pixel is first said to be background or not; a surface pixel whose
// prediction is not a surface (a silhouette the prediction missed) is predicted from its nearest
// surface neighbour instead, so an edge one pixel off costs a flag, not a jump across 2^30.
inline uint32_t surface_prediction(const SliceJob& j, int x, int y, uint32_t p) {
    if (j.map->surface(p)) return p;
    const bool left = x > 0, top = y > j.y0;
    if (left && j.map->surface(j.codes(x - 1, y))) return j.codes(x - 1, y);
    if (top && j.map->surface(j.codes(x, y - 1))) return j.codes(x, y - 1);
    if (above_right_known(j, x, y) && j.map->surface(j.codes(x + 1, y - 1)))
        return j.codes(x + 1, y - 1);
    if (left && top && j.map->surface(j.codes(x - 1, y - 1))) return j.codes(x - 1, y - 1);
    return p;
}

// A pixel the block's prediction misses may take the other prediction instead, for one flag. In
// an inter frame that is the temporal one in a spatial or plane block and the spatial one in a
// temporal block (a silhouette the reprojection put a pixel off, a surface the spatial prediction
// drifted from); in a key frame's view depth, of the left, above and (where the encoder knows it)
// above-right codes the one farther from p when it is a step away (an edge the median or the plane
// put on the wrong side, a silhouette coming down from the right). Returns p where that
// prediction is the same or no surface. Version 17: a residual from it may follow.
inline uint32_t other_prediction(const SliceJob& j, int x, int y, bool temporal, uint32_t p) {
    if (j.temporal.empty()) {
        if (!j.map->view || x == 0 || y == j.y0) return p;
        const uint32_t a = j.codes(x - 1, y), b = j.codes(x, y - 1);
        uint32_t q = std::abs(int64_t(p) - int64_t(a)) <= std::abs(int64_t(p) - int64_t(b)) ? b : a;
        if (above_right_known(j, x, y)) {
            const uint32_t d = j.codes(x + 1, y - 1);
            if (j.map->surface(d) &&
                std::abs(int64_t(p) - int64_t(d)) > std::abs(int64_t(p) - int64_t(q)))
                q = d;
        }
        return j.map->surface(q) && step_between(*j.map, q, p) ? q : p;
    }
    const uint32_t q = predict(j, x, y, !temporal);
    return j.map->surface(q) ? q : p;
}

// Whether the encoder codes c from the other prediction o rather than from p' (version 17): where
// c lies a whole number of residual steps s from o, and nearer it than p' or not a whole number
// of steps from p'.
inline bool from_other(uint32_t c, uint32_t base, uint32_t other, uint32_t s) {
    const int64_t ro = int32_t(c - other), rb = int32_t(c - base);
    return ro % int64_t(s) == 0 && (rb % int64_t(s) != 0 || std::abs(ro) < std::abs(rb));
}

// A third prediction in inter frames in view mode, for a pixel both others miss: of its four
// neighbours' temporal codes, the one farthest from p when it is more than a residual step away
// (a silhouette the reprojection put a pixel off, which the spatial prediction, reading only
// codes to the left and above, places wrongly too); p where none is.
inline uint32_t across_prediction(const SliceJob& j, int x, int y, uint32_t p) {
    if (j.temporal.empty() || !j.map->view) return p;
    uint32_t q = p;
    int64_t farthest = 0;
    for (const auto& [dx, dy] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
        const int nx = x + dx, ny = y + dy;
        if (nx < 0 || ny < 0 || nx >= j.width || ny >= j.temporal.height) continue;
        const uint32_t t = j.temporal(nx, ny);
        const int64_t d = std::abs(int64_t(t) - int64_t(p));
        if (j.map->surface(t) && d > farthest) farthest = d, q = t;
    }
    return step_between(*j.map, q, p) ? q : p;
}

// Which of the prediction and the left, above, above-left and above-right codes are background:
// a silhouette against the background continues its slope from the row above.
inline int background_context(const SliceJob& j, int x, int y, uint32_t p) {
    const uint32_t empty = j.map->empty();
    const bool top = y > j.y0;
    return 16 * (p == empty) + 8 * (x > 0 && j.codes(x - 1, y) == empty) +
           4 * (top && j.codes(x, y - 1) == empty) +
           2 * (top && x > 0 && j.codes(x - 1, y - 1) == empty) +
           (top && x + 1 < j.width && j.codes(x + 1, y - 1) == empty);
}

// Inter frames in view mode (version 18), for the contexts: what the staircase of the decoded rows
// above says of a pixel beside a step of the temporal prediction along its row (a silhouette's
// side): 0 nothing (no step, or no staircase), 1 the line through where the step lies in the
// kStairRows rows above, continued to this row, puts the pixel on the side the prediction does,
// 2 on the other (there a silhouette comes a pixel off about half the time).
constexpr int kStairRows = 6;
inline int staircase(const SliceJob& j, int x, int y) {
    if (j.temporal.empty() || !j.map->view || y - kStairRows < j.y0 || x < 4 || x + 4 > j.width)
        return 0;
    const int64_t far = 4 * int64_t(j.map->residual_step);
    auto apart = [&](uint32_t a, uint32_t b) {
        return a <= kMaxViewCode && b <= kMaxViewCode && std::abs(int64_t(a) - int64_t(b)) > far;
    };
    int edge = -1;  // the step lies between edge - 1 and edge
    if (apart(j.temporal(x - 1, y), j.temporal(x, y)))
        edge = x;
    else if (apart(j.temporal(x, y), j.temporal(x + 1, y)))
        edge = x + 1;
    if (edge < 0) return 0;
    const int64_t a = j.temporal(edge - 1, y), b = j.temporal(edge, y);
    auto b_side = [&](uint32_t c) { return std::abs(int64_t(c) - b) < std::abs(int64_t(c) - a); };
    int64_t sum = 0, weighted = 0;
    for (int k = 1, near = edge; k <= kStairRows; ++k) {
        int found = -1;
        for (int c = std::max(1, near - 3); c <= std::min(j.width - 1, near + 3) && found < 0; ++c)
            if (!b_side(j.codes(c - 1, y - k)) && b_side(j.codes(c, y - k))) found = c;
        if (found < 0) return 0;
        sum += found, weighted += int64_t(k) * found, near = found;
    }
    // The least-squares line through (k, column) for k = 1..K, at k = 0.
    const int64_t n = kStairRows, sk = n * (n + 1) / 2, skk = n * (n + 1) * (2 * n + 1) / 6;
    const int64_t numerator = sum * skk - weighted * sk, denominator = n * skk - sk * sk;
    const int64_t predicted = (2 * numerator + denominator) / (2 * denominator);
    return (x >= edge) != (x >= predicted) ? 2 : 1;
}

// Whether the staircase above puts a pixel of a block's first row on the other side of the
// temporal prediction's step (version 18): such a block seldom goes without residuals.
inline int stairs_in_row(const SliceJob& j, int bx, int by, int bw) {
    for (int x = bx; x < bx + bw; ++x)
        if (staircase(j, x, by) == 2) return 1;
    return 0;
}

// A residual's class: what the staircase above says (`stair`, version 18), at an edge (p no
// surface, or a step from the left or above code) or not, beside a step in the temporal
// prediction (a third prediction exists, version 14) or not, and the magnitude of the residuals
// to the left and above.
inline int residual_context(const SliceJob& j, int x, int y, uint32_t p, int stair) {
    const bool edge = !j.map->surface(p) || (x > 0 && step_between(*j.map, j.codes(x - 1, y), p)) ||
                      (y > j.y0 && step_between(*j.map, j.codes(x, y - 1), p));
    const bool across = j.temporal.empty() ? y > j.y0 && x + 1 < j.width &&
                                                 step_between(*j.map, j.codes(x + 1, y - 1), p)
                                           : across_prediction(j, x, y, p) != p;
    return 16 * stair + 4 * (edge + 2 * across) +
           magnitude_class(x > 0 ? j.residuals(x - 1, y) : 0, y > j.y0 ? j.residuals(x, y - 1) : 0);
}

// A block's flags are coded in the context of its left and above neighbours in the slice: how
// many of them are temporal, and how many have residuals (silhouettes run across blocks).
inline int temporal_context(const std::vector<uint8_t>& row, const std::vector<uint8_t>& above,
                            int b) {
    return (b > 0 && (row[b - 1] & kTemporalBlock)) +
           (!above.empty() && (above[b] & kTemporalBlock));
}
inline int zero_context(const std::vector<uint8_t>& row, const std::vector<uint8_t>& above, int b) {
    return (b > 0 && !(row[b - 1] & kZeroBlock)) + (!above.empty() && !(above[b] & kZeroBlock));
}

// What the temporal prediction shows of a block, known to both sides before its flags: 0 no
// step between neighbouring codes, 1 a step (a silhouette, where residuals gather), 2 a pixel
// nothing landed on (block_shows, for the whole frame before the slices). Key frames (version
// 17): what the row above the block shows, 0 one surface, 1 an edge or background beside a
// surface, 2 background only (or no row above).
inline int reprojection_class(const SliceJob& j, int bx, int by, int bw) {
    if (j.temporal.empty()) {
        if (by == j.y0) return 2;
        bool surface = false, background = false, step = false;
        uint32_t last = 0;
        for (int x = std::max(bx - 1, 0); x < std::min(bx + bw + 1, j.width); ++x) {
            const uint32_t c = j.codes(x, by - 1);
            if (c == j.map->empty()) {
                background = true;
                continue;
            }
            step |= surface && step_between(*j.map, c, last);
            surface = true;
            last = c;
        }
        return !surface ? 2 : (background || step) ? 1 : 0;
    }
    return j.shows(bx / kBlock, by / kBlock);
}

// Cost estimate of coding a block's residuals.
inline uint64_t residual_cost(int32_t r) {
    return r == 0 ? 0 : 2 + 2 * uint64_t(std::bit_width(uint32_t(std::abs(int64_t(r)))));
}

// Cost estimate of one pixel of a block with residuals (its codes to the left and above known):
// the background flag, then the residual from the surface prediction.
inline uint64_t pixel_cost(const SliceJob& j, int x, int y, bool temporal, uint32_t p) {
    const uint32_t c = j.codes(x, y);
    if (c == p) return 0;
    if (c == j.map->empty()) return 1;
    const uint32_t other = other_prediction(j, x, y, temporal, p);
    const uint32_t base = surface_prediction(j, x, y, p), s = j.map->residual_step;
    if (other != p && from_other(c, base, other, s))
        return 3 + residual_cost(int32_t(c - other) / int32_t(s));
    const uint32_t across = across_prediction(j, x, y, p);
    const bool has_across = across != p && across != other;
    if (has_across && c == across) return 3 + (other != p);
    return 1 + (other != p) + has_across + residual_cost(int32_t(c - base) / int32_t(s));
}

}  // namespace

void view_code_row_reference(const ViewCodeRow& r, int i_begin, int i_end) {
    for (int i = i_begin; i < i_end; ++i) {
        const float z = r.depth[i];
        r.out[i] = std::isnan(z)   ? kNoPrediction
                   : z == INFINITY ? kInfCode
                   : !(z > 0.0f && z < INFINITY)
                       ? kInvalidCode
                       : uint32_t(std::min(std::nearbyint(1.0 / double(z) / r.step),
                                           double(kMaxViewCode)));
    }
}

void view_depth_row_reference(const ViewDepthRow& r, int i_begin, int i_end) {
    for (int i = i_begin; i < i_end; ++i) {
        const uint32_t c = r.codes[i];
        const float z = float(1.0 / (c == 0 ? 0.5 * r.step : double(c) * r.step));
        r.out[i] = c <= kMaxViewCode ? z
                   : c == kInfCode   ? std::numeric_limits<float>::infinity()
                                     : std::numeric_limits<float>::quiet_NaN();
    }
}

void shows_row_reference(const ShowsRow& r, int i_begin, int i_end) {
    auto apart = [&](uint32_t a, uint32_t b) { return std::max(a, b) - std::min(a, b) > r.step; };
    for (int i = i_begin; i < i_end; ++i) {
        const uint32_t t = r.temporal[i];
        const uint8_t shows =
            t == kNoPrediction ? 2
            : (i % kBlock != 0 && apart(t, r.temporal[i - 1])) || (r.above && apart(t, r.above[i]))
                ? 1
                : 0;
        r.out[i] = std::max(r.out[i], shows);
    }
}

void view_keep_row_reference(const ViewKeepRow& r, int i_begin, int i_end) {
    for (int i = i_begin; i < i_end; ++i) {
        const float z = r.source[i];
        const uint32_t t = r.temporal[i];
        r.keep[i] = t <= kMaxViewCode && z > 0.0f && z < INFINITY &&
                    view_code_within(1.0 / double(z), t, r.step, r.displacement,
                                     r.share ? double(r.share[i]) : 1.0);
    }
}

namespace {

// View mode: the code sent for the source depth at (x, y) predicted by p. Any code whose inverse
// depth is close enough to the truth keeps the reprojection error within the bound: p itself
// when it is such a code, else the surface prediction, or the other prediction where that takes
// fewer steps, plus the residual steps that come nearest the truth (within q / 2). The allowance
// shrinks by (1 - B/z)^2 for points near the camera (docs/bitstream.md). A key frame keeps p only
// within 4/5 of the allowance (view_share): later frames transport its depth, and values left at
// the edge of the bound would leave it at the first noise of that transport, a residual each. The
// other prediction, then the third (inter frames), when it is close enough, costs less than a
// residual. A pixel may be allowed a multiple of the bound (`SliceJob::share`, view_share); its
// residual still takes it nearest the truth (the smallest residual within the wider bound left the
// next frames' predictions farther off: key depth +4 %).
uint32_t choose_view_code(const SliceJob& j, int x, int y, bool temporal, uint32_t p) {
    const Mapping& map = *j.map;
    const float z = j.source.empty() ? INFINITY : j.source(x, y);
    if (z == INFINITY) return kInfCode;  // background: a flag
    // map.code(z), a rounding, is needed only for a residual: the tests first.
    const bool valid = z > 0.0f && std::isfinite(z);
    const double w = valid ? 1.0 / double(z) : 0.0;
    const double share = j.share.empty() ? j.uniform_share : double(j.share(x, y));
    if (valid && p <= kMaxViewCode && view_code_within(w, p, map.step, map.displacement, share))
        return p;
    const uint32_t other = other_prediction(j, x, y, temporal, p);
    if (valid) {
        if (other != p && other <= kMaxViewCode &&
            view_code_within(w, other, map.step, map.displacement, share))
            return other;
        const uint32_t across = across_prediction(j, x, y, p);
        if (across != p && across != other && across <= kMaxViewCode &&
            view_code_within(w, across, map.step, map.displacement, share))
            return across;
    }
    const int64_t base = surface_prediction(j, x, y, p), s = kViewResidualStep;
    if (!valid)  // NaN: any code above 2^30 + 1
        return uint32_t(base + std::max<int64_t>(0, (kInvalidCode - base + s - 1) / s) * s);
    const uint32_t k = map.code(z);
    auto nearest = [&](int64_t from) {  // whole steps from `from`, nearest the truth
        int64_t c = from + (int64_t(k) - from + (k >= from ? s / 2 : -(s / 2))) / s * s;
        if (c < 0) c += s;  // the nearest code of 0..2^30 instead
        if (c > kMaxViewCode) c -= s;
        return c;
    };
    int64_t c = nearest(base);
    if (other != p && other <= kMaxViewCode) {  // fewer steps from the other prediction
        const int64_t stepped = nearest(other);
        if (std::abs(stepped - int64_t(other)) < std::abs(c - base)) c = stepped;
    }
    return uint32_t(c);
}

// The estimated cost of a block predicted temporally or spatially; in view mode, its codes are
// chosen for that prediction on the way. A mode whose cost reaches `enough` cannot be chosen: its
// pixels are left at the first row that reaches it (the chosen mode's codes are made again).
uint64_t block_cost(SliceJob& j, int bx, int by, int bw, int bh, int mode,
                    uint64_t enough = UINT64_MAX) {
    const bool temporal = mode == kTemporalMode;
    uint64_t cost = 0;
    for (int y = by; y < by + bh && cost < enough; ++y)
        for (int x = bx; x < bx + bw; ++x) {
            const uint32_t p = block_prediction(j, x, y, mode);
            if (j.map->view) {
                // Background (or no source) is its flag's code: choose_view_code's first answer.
                const bool background = j.source.empty() || j.source(x, y) == INFINITY;
                j.codes(x, y) = background ? kInfCode : choose_view_code(j, x, y, temporal, p);
                if (background && p == kInfCode) continue;  // pixel_cost: the prediction, 0
            }
            cost += pixel_cost(j, x, y, temporal, p);
        }
    return cost;
}

// The least-squares plane through the inverse depth of a block's surface pixels, in codes, its
// offset in whole steps from the prediction's; false where fewer than three pixels are surface or
// the plane leaves the limits.
bool fit_plane(const SliceJob& j, int bx, int by, int bw, int bh, const Plane& predicted,
               Plane& out) {
    std::array<std::array<double, 7>, 7> a{};
    std::array<double, 7> rhs{}, sol{};
    int n = 0;
    for (int y = by; y < by + bh; ++y)
        for (int x = bx; x < bx + bw; ++x) {
            const float z = j.source(x, y);
            if (!(z > 0.0f && z < INFINITY)) continue;
            const double k = 1.0 / double(z) / j.map->step;
            const double v[3] = {1.0, x - bx - 3.5, y - by - 3.5};
            for (int r = 0; r < 3; ++r) {
                for (int c = 0; c < 3; ++c) a[r][c] += v[r] * v[c];
                rhs[r] += v[r] * k;
            }
            ++n;
        }
    if (n < 3 || !fit::solve(a, rhs, 3, sol)) return false;
    const double limit = double(kMaxPlaneSlope);
    if (!(std::abs(sol[1]) < limit && std::abs(sol[2]) < limit && std::abs(sol[0]) < limit))
        return false;
    out.gx = std::llround(sol[1]);
    out.gy = std::llround(sol[2]);
    out.c = predicted.c + std::llround((sol[0] - double(predicted.c)) / double(kPlaneOffsetStep)) *
                              kPlaneOffsetStep;
    return plane_in_range(out);
}

// The estimated cost of a plane's parameters against their prediction.
uint64_t plane_cost(const Plane& q, const Plane& predicted) {
    auto one = [](int64_t r) {
        return r == 0 ? 1 : 2 + 2 * uint64_t(std::bit_width(uint64_t(std::abs(r))));
    };
    return 1 + one((q.c - predicted.c) / kPlaneOffsetStep) + one(q.gx - predicted.gx) +
           one(q.gy - predicted.gy);
}

void encode_plane(RangeEncoder& rc, Models& m, const Plane& q, const Plane& predicted,
                  bool from_neighbour) {
    encode_int(rc, m.plane_offset[from_neighbour], (q.c - predicted.c) / kPlaneOffsetStep);
    encode_int(rc, m.plane_slope[from_neighbour][0], q.gx - predicted.gx);
    encode_int(rc, m.plane_slope[from_neighbour][1], q.gy - predicted.gy);
}

bool decode_plane(RangeDecoder& rc, Models& m, const Plane& predicted, bool from_neighbour,
                  Plane& q) {
    int64_t dc = 0, dx = 0, dy = 0;
    if (!decode_int(rc, m.plane_offset[from_neighbour], dc) ||
        !decode_int(rc, m.plane_slope[from_neighbour][0], dx) ||
        !decode_int(rc, m.plane_slope[from_neighbour][1], dy))
        return false;
    q = {predicted.c + dc * kPlaneOffsetStep, predicted.gx + dx, predicted.gy + dy};
    return plane_in_range(q);
}

// The encoder decides each block before coding any: temporal prediction first, the spatial one
// (the costly inverse-depth median) only where the temporal one is not exact, and in view mode a
// plane fitted to the block where neither is. Residuals of
// the whole block row are stored before they are coded; the contexts read the same values the
// decoder has at that point.
void encode_slice(SliceJob& j, const ModelCarry& carry, int slice, std::vector<uint8_t>& bytes,
                  std::vector<uint8_t>& block_flags) {
    RangeEncoder rc(bytes);
    Models m;
    carry.load(slice, m);
    const bool inter = !j.temporal.empty();
    const int blocks = (j.width + kBlock - 1) / kBlock;
    block_flags.assign(std::size_t(blocks), 0);
    std::vector<uint8_t> above;
    std::vector<Plane> planes(static_cast<std::size_t>(blocks)), above_planes;
    const bool try_planes = j.map->view && !j.source.empty();
    // View mode: which pixels of the block row keep their temporal prediction (most of them).
    const bool keep_test = inter && j.map->view && !j.source.empty();
    std::vector<uint8_t> keep(keep_test ? std::size_t(kBlock) * j.width : 0);
    for (int by = j.y0; by < j.y1; by += kBlock) {
        if (by > j.y0) {
            above = block_flags;
            above_planes = planes;
        }
        const int bh = std::min(kBlock, j.y1 - by);
        if (keep_test)
            for (int y = by; y < by + bh; ++y)
                view_keep_row({.source = j.source.row(y),
                               .temporal = j.temporal.row(y),
                               .count = j.width,
                               .step = j.map->step,
                               .displacement = j.map->displacement,
                               .keep = &keep[std::size_t(y - by) * j.width],
                               .share = j.share.empty() ? nullptr : j.share.row(y)});
        for (int b = 0; b < blocks; ++b) {
            const int bx = b * kBlock, bw = std::min(kBlock, j.width - bx);
            int mode = inter ? kTemporalMode : kSpatialMode, last = mode;
            uint64_t cost = 0;
            if (inter) {
                // Most blocks of a moving camera's depth are predicted exactly (no code equals
                // kNoPrediction): with the codes known, a plain comparison finds them.
                bool exact = true;
                for (int y = by; y < by + bh && exact; ++y)
                    exact = keep_test
                                ? std::all_of(&keep[std::size_t(y - by) * j.width + bx],
                                              &keep[std::size_t(y - by) * j.width + bx + bw],
                                              [](uint8_t k) { return k != 0; })
                                : !j.map->view && std::equal(&j.codes(bx, y), &j.codes(bx, y) + bw,
                                                             &j.temporal(bx, y));
                if (exact && j.map->view)  // the codes are the predictions
                    for (int y = by; y < by + bh; ++y)
                        std::copy_n(&j.temporal(bx, y), bw, &j.codes(bx, y));
                if (!exact) cost = block_cost(j, bx, by, bw, bh, kTemporalMode);
            }
            if (!inter || cost > 0) {
                const uint64_t spatial_cost =
                    block_cost(j, bx, by, bw, bh, kSpatialMode, inter ? cost : UINT64_MAX);
                last = kSpatialMode;
                if (!inter || spatial_cost < cost) {
                    mode = kSpatialMode;
                    cost = spatial_cost;
                }
            }
            // A plane, where the block's surface is smooth enough that its parameters cost less
            // than the residuals of the median's drift.
            const Plane predicted =
                try_planes && cost > 0
                    ? predicted_plane(j, b, by, block_flags, above, planes, above_planes)
                    : Plane{};
            Plane fitted;
            if (try_planes && cost > 0 && fit_plane(j, bx, by, bw, bh, predicted, fitted)) {
                j.plane = fitted;
                j.plane_x = bx;
                j.plane_y = by;
                // Beyond cost + kZeroFlags a plane's pixels alone cost more than the block.
                const uint64_t pixels =
                    block_cost(j, bx, by, bw, bh, kPlaneMode, cost + kZeroFlags);
                last = kPlaneMode;
                // The estimates leave out the zero flags of a block with residuals (one per
                // pixel, kZeroFlags bits in all); a plane that leaves none saves them.
                if (pixels + plane_cost(fitted, predicted) + (pixels > 0 ? kZeroFlags : 0) <
                    cost + kZeroFlags) {
                    mode = kPlaneMode;
                    cost = pixels;
                }
            }
            if (j.map->view && mode != last)
                block_cost(j, bx, by, bw, bh, mode);  // the chosen prediction's codes again
            const int shows = reprojection_class(j, bx, by, bw);
            rc.tally_into(&j.bits.flags);
            if (inter)
                rc.bit(m.temporal[shows][temporal_context(block_flags, above, b)],
                       mode == kTemporalMode);
            if (j.map->view && mode != kTemporalMode) {
                rc.bit(m.plane[shows][plane_context(block_flags, above, b)], mode == kPlaneMode);
                if (mode == kPlaneMode) {
                    rc.tally_into(&j.bits.planes);
                    encode_plane(rc, m, fitted, predicted,
                                 plane_context(block_flags, above, b) > 0);
                    rc.tally_into(&j.bits.flags);
                }
            }
            planes[std::size_t(b)] = mode == kPlaneMode ? fitted : Plane{};
            j.plane_blocks += mode == kPlaneMode;
            rc.bit(m.zero_block[mode][shows][zero_context(block_flags, above, b)]
                               [stairs_in_row(j, bx, by, bw)],
                   cost == 0);
            j.zero_blocks += cost == 0;
            block_flags[b] = (mode == kTemporalMode ? kTemporalBlock : 0) |
                             (mode == kPlaneMode ? kPlaneBlock : 0) | (cost == 0 ? kZeroBlock : 0);
            if (cost == 0) {
                for (int y = by; y < by + bh; ++y)
                    std::fill(&j.residuals(bx, y), &j.residuals(bx, y) + bw, 0u);
                continue;
            }
            for (int y = by; y < by + bh; ++y)
                for (int x = bx; x < bx + bw; ++x)
                    j.predictions(x, y) = block_prediction(j, x, y, mode);
        }
        for (int y = by; y < by + bh; ++y)
            for (int b = 0; b < blocks; ++b) {
                const uint8_t flags = block_flags[b];
                if (flags & kZeroBlock) continue;
                for (int x = b * kBlock; x < std::min(j.width, (b + 1) * kBlock); ++x) {
                    const uint32_t p = j.predictions(x, y), c = j.codes(x, y);
                    const bool background = c == j.map->empty();
                    rc.tally_into(!inter                                      ? &j.bits.key
                                  : !j.share.empty() && j.share(x, y) == 1.0f ? &j.bits.objects
                                  : j.temporal(x, y) == kNoPrediction         ? &j.bits.revealed
                                                                              : &j.bits.seen);
                    rc.bit(m.background[background_context(j, x, y, p)], background);
                    j.residuals(x, y) = 0;
                    if (background) continue;
                    const uint32_t base = surface_prediction(j, x, y, p);
                    const int stair = staircase(j, x, y);
                    IntModel<24>& model =
                        m.residual[flags & 1][residual_context(j, x, y, p, stair)];
                    rc.bit(model.zero, c != base);
                    if (c == base) continue;
                    const uint32_t other = other_prediction(j, x, y, flags & 1, p);
                    if (other != p) {
                        const bool use = from_other(c, base, other, j.map->residual_step);
                        rc.bit(m.other[flags & 1][stair], use);
                        if (use) {
                            const int32_t r = int32_t(c - other) / int32_t(j.map->residual_step);
                            encode_int(rc, m.other_residual[flags & 1], r);
                            // For the contexts: a pixel that missed.
                            j.residuals(x, y) = r == 0 ? 1u : uint32_t(r);
                            continue;
                        }
                    }
                    const uint32_t across = across_prediction(j, x, y, p);
                    if (across != p && across != other) {
                        rc.bit(m.across[flags & 1][stair], c == across);
                        if (c == across) {
                            j.residuals(x, y) = 1;
                            continue;
                        }
                    }
                    const int32_t r = int32_t(c - base) / int32_t(j.map->residual_step);
                    j.residuals(x, y) = uint32_t(r);
                    encode_nonzero_int(rc, model, r);
                }
            }
    }
    rc.finish();
    carry.save(slice, m);
}

// Codes x0..x1 - 1 of row y are their predictions (a block without residuals, not a plane): as
// predict() gives them, with the left code carried along the run (the spatial median of a left
// and a top code that are equal is that code, as in the background).
void predict_run(SliceJob& j, int x0, int x1, int y, bool temporal) {
    std::fill(&j.residuals(x0, y), &j.residuals(x0, y) + (x1 - x0), 0u);
    uint32_t* codes = &j.codes(0, y);
    if (x0 == 0 || y == j.y0 || j.map->lossless) {
        for (int x = x0; x < x1; ++x) codes[x] = predict(j, x, y, temporal);
        return;
    }
    const uint32_t* top = &j.codes(0, y - 1);
    const uint32_t* reprojected = temporal ? &j.temporal(0, y) : nullptr;
    uint32_t left = codes[x0 - 1];
    for (int x = x0; x < x1; ++x) {
        uint32_t p = reprojected ? reprojected[x] : kNoPrediction;
        if (p == kNoPrediction) p = top[x] == left ? left : median_edge(left, top[x], top[x - 1]);
        codes[x] = left = p;
    }
}

bool decode_slice(SliceJob& j, const ModelCarry& carry, int slice, std::span<const uint8_t> bytes) {
    RangeDecoder rc(bytes);
    Models m;
    carry.load(slice, m);
    const bool inter = !j.temporal.empty();
    const int blocks = (j.width + kBlock - 1) / kBlock;
    std::vector<uint8_t> flags(std::size_t(blocks), 0), above;
    std::vector<Plane> planes(static_cast<std::size_t>(blocks)), above_planes;
    // Blocks whose codes are their temporal prediction, which every pixel has: copied.
    std::vector<uint8_t> copied(std::size_t(blocks) + 1, 0);
    for (int by = j.y0; by < j.y1; by += kBlock) {
        const int bh = std::min(kBlock, j.y1 - by);
        if (by > j.y0) {
            above = flags;
            above_planes = planes;
        }
        for (int b = 0; b < blocks; ++b) {
            const int bw = std::min(kBlock, j.width - b * kBlock);
            const int shows = reprojection_class(j, b * kBlock, by, bw);
            const bool temporal =
                inter && rc.bit(m.temporal[shows][temporal_context(flags, above, b)]);
            const int context = plane_context(flags, above, b);
            const bool plane = j.map->view && !temporal && rc.bit(m.plane[shows][context]);
            planes[std::size_t(b)] = {};
            if (plane &&
                !decode_plane(rc, m, predicted_plane(j, b, by, flags, above, planes, above_planes),
                              context > 0, planes[std::size_t(b)]))
                return false;
            const int mode = temporal ? kTemporalMode : plane ? kPlaneMode : kSpatialMode;
            const bool zero = rc.bit(m.zero_block[mode][shows][zero_context(flags, above, b)]
                                                 [stairs_in_row(j, b * kBlock, by, bw)]);
            flags[b] = (temporal ? kTemporalBlock : 0) | (plane ? kPlaneBlock : 0) |
                       (zero ? kZeroBlock : 0);
            copied[std::size_t(b)] = temporal && zero && shows != 2;
            j.zero_blocks += zero;
            j.plane_blocks += plane;
        }
        for (int y = by; y < by + bh; ++y)
            for (int x = 0; x < j.width; ++x) {
                int b = x / kBlock;
                if (copied[std::size_t(b)]) {  // x starts the block: a run of such blocks at once
                    while (copied[std::size_t(b) + 1]) ++b;
                    const int end = std::min(j.width, (b + 1) * kBlock);
                    std::copy(&j.temporal(x, y), &j.temporal(x, y) + (end - x), &j.codes(x, y));
                    std::fill(&j.residuals(x, y), &j.residuals(x, y) + (end - x), 0u);
                    x = end - 1;
                    continue;
                }
                const bool temporal = flags[b] & kTemporalBlock;
                if ((flags[b] & (kZeroBlock | kPlaneBlock)) == kZeroBlock) {
                    const int end = std::min(j.width, (b + 1) * kBlock);
                    predict_run(j, x, end, y, temporal);
                    x = end - 1;
                    continue;
                }
                const uint32_t p = (flags[b] & kPlaneBlock)
                                       ? plane_code(planes[std::size_t(b)], x - b * kBlock, y - by)
                                       : predict(j, x, y, temporal);
                if (flags[b] & kZeroBlock) {
                    j.residuals(x, y) = 0;
                    j.codes(x, y) = p;
                    continue;
                }
                if (rc.bit(m.background[background_context(j, x, y, p)])) {
                    j.residuals(x, y) = 0;
                    j.codes(x, y) = j.map->empty();
                    continue;
                }
                const int stair = staircase(j, x, y);
                IntModel<24>& model = m.residual[temporal][residual_context(j, x, y, p, stair)];
                const uint32_t base = surface_prediction(j, x, y, p);
                j.residuals(x, y) = 0;
                j.codes(x, y) = base;
                if (!rc.bit(model.zero)) continue;
                const uint32_t other = other_prediction(j, x, y, temporal, p);
                if (other != p && rc.bit(m.other[temporal][stair])) {
                    int64_t r = 0;
                    if (!decode_int(rc, m.other_residual[temporal], r)) return false;
                    j.residuals(x, y) = r == 0 ? 1u : uint32_t(r);
                    j.codes(x, y) = other + uint32_t(r) * j.map->residual_step;
                    continue;
                }
                const uint32_t across = across_prediction(j, x, y, p);
                if (across != p && across != other && rc.bit(m.across[temporal][stair])) {
                    j.residuals(x, y) = 1;
                    j.codes(x, y) = across;
                    continue;
                }
                int64_t r = 0;
                if (!decode_nonzero_int(rc, model, r)) return false;
                j.residuals(x, y) = uint32_t(r);
                j.codes(x, y) = base + uint32_t(r) * j.map->residual_step;
            }
        if (rc.overrun() > 8) return false;
    }
    if (rc.overrun() > 8) return false;
    carry.save(slice, m);
    return true;
}

// Two landings d pixels apart whose 1/z differ by at most d of this are one surface in the plane
// fit and the crack fill (beside the relative test, kSameSurface): the step a bound of 0.25 px
// takes, whatever coarser bound the stream has. A far ground seen at a grazing angle changes by
// about that much a pixel and by far more than 1/32 of its 1/z; with the stream's own step, the
// coarser bounds above qp 34 bridged silhouettes (stroll 160x96, qp 46: colour -0.45 dB).
float surface_step(const SequenceParams& sp, const Mapping& map) {
    return float(map.step * kViewCodesPerStep * std::min(1.0, 0.25 / double(sp.view_error)));
}

// Codes of the reference depth seen from `camera`; empty on key frames or without reference depth.
void temporal_codes(const FrameContext& fc, const Camera& camera, const Mapping& map,
                    Image<uint32_t>& out) {
    if (fc.key || !fc.reference || fc.reference->depth.empty()) {
        out.clear();
        return;
    }
    const int w = fc.sp->width, h = fc.sp->height;
    Image<float>& projected = fc.work->projected_depth;
    ensure_size(projected, w, h);
    // Objects move the reference's pixels only when it is the frame their motion starts from.
    const Camera& rc = fc.reference->camera;
    const bool previous = camera.prev_view == rc.view && camera.prev_projection == rc.projection;
    reproject_depth(rc, fc.reference->depth.view(), camera, projected.view(),
                    previous ? fc.reference->owner.view() : ImageView<const uint32_t>{},
                    previous ? fc.objects : std::span<const ObjectMotion>{},
                    map.view ? surface_step(*fc.sp, map) : 0.0f);
    ensure_size(out, w, h);
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            if (map.view) {
                view_code_row(
                    {.depth = &projected(0, y), .count = w, .step = map.step, .out = &out(0, y)});
                continue;
            }
            for (int x = 0; x < w; ++x) {
                const float z = projected(x, y);
                out(x, y) = std::isnan(z) ? kNoPrediction : map.code(z);
            }
        }
    });
}

// Inter frames: what the temporal prediction shows of each block (reprojection_class), for the
// whole frame before the slices, a block row per task.
void block_shows(const Image<uint32_t>& temporal, uint32_t step, Image<uint8_t>& out) {
    const int w = temporal.width(), h = temporal.height();
    const int columns = (w + kBlock - 1) / kBlock, rows = (h + kBlock - 1) / kBlock;
    ensure_size(out, columns, rows);
    parallel_for(0, rows, [&](int r0, int r1) {
        std::vector<uint8_t> pixels(static_cast<std::size_t>(w));
        for (int r = r0; r < r1; ++r) {
            std::fill(pixels.begin(), pixels.end(), uint8_t(0));
            for (int y = r * kBlock; y < std::min(h, (r + 1) * kBlock); ++y)
                shows_row({.temporal = &temporal(0, y),
                           .above = y > r * kBlock ? &temporal(0, y - 1) : nullptr,
                           .count = w,
                           .step = step,
                           .out = pixels.data()});
            for (int b = 0; b < columns; ++b)
                out(b, r) = *std::max_element(pixels.begin() + b * kBlock,
                                              pixels.begin() + std::min(w, (b + 1) * kBlock));
        }
    });
}

std::vector<SliceJob> slice_jobs(const SequenceParams& sp, const Mapping& map,
                                 Image<uint32_t>& codes, const Image<uint32_t>& temporal,
                                 Image<uint32_t>& residuals, Image<uint8_t>& shows,
                                 Image<uint32_t>* predictions = nullptr) {
    if (!temporal.empty()) block_shows(temporal, map.residual_step, shows);
    std::vector<SliceJob> jobs;
    for (int s = 0; s < sp.slices; ++s) {
        const int y0 = std::min(sp.height, sp.slice_begin(s) * kMb);
        const int y1 = std::min(sp.height, sp.slice_begin(s + 1) * kMb);
        jobs.push_back({&map, sp.width, y0, y1, codes.view(), temporal.view(), residuals.view(),
                        predictions ? predictions->view() : ImageView<uint32_t>{}});
        jobs.back().shows = shows.view();
    }
    return jobs;
}

void depth_from_codes(const Mapping& map, const Image<uint32_t>& codes, Image<float>& out) {
    ensure_size(out, codes.width(), codes.height());
    parallel_for(0, codes.height(), [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            if (map.view) {  // map.depth of each code (most differ from their left)
                view_depth_row({.codes = &codes(0, y),
                                .count = codes.width(),
                                .step = map.step,
                                .out = &out(0, y)});
                continue;
            }
            uint32_t last = codes(0, y);
            float z = map.depth(last);
            for (int x = 0; x < codes.width(); ++x) {
                const uint32_t c = codes(x, y);
                if (c != last) {
                    last = c;
                    z = map.depth(c);
                }
                out(x, y) = z;
            }
        }
    });
}

}  // namespace

// Codes are log2(z) / step rounded: the decoded z is within 2^(step / 2) - 1 of the truth; a
// little margin keeps float rounding of the result inside the bound.
double SequenceParams::depth_step() const {
    return 2.0 * exact_log2(1.0 + 0.999 * double(depth_error));
}

namespace {

// View mode: the multiple of the frame's bound each pixel may use, or empty (`uniform` everywhere).
// Where an object's travel made the frame's step finer than the cameras' (frame_view_step), only
// the objects' pixels need it; the others keep the cameras' bound, as many times coarser. A key
// frame keeps kKeyShare of that (choose_view_code), but where its camera stands still and no object
// moves the pixel: the next frames take that depth where it lies (shadows' key depth -7 %). A
// camera that only says it stands still (previous = current on a first frame) and then moves
// costs residuals where the transport leaves the bound (0.9 of it on moving cameras' key frames:
// +1.4 to +1.6 % depth).
constexpr float kKeyShare = 0.8f;
ImageView<const float> view_share(const FrameContext& fc, const Mapping& map, const Camera& camera,
                                  float& uniform) {
    const bool still =
        fc.key && camera.prev_view == camera.view && camera.prev_projection == camera.projection;
    uniform = fc.key && !still ? kKeyShare : 1.0f;
    const double ratio = double(fc.camera_step) / (map.step * kViewCodesPerStep);
    const bool finer = ratio > 1.0;
    if (!map.view || fc.ids.empty() || fc.objects.empty() || !(finer || still)) return {};
    const float moving_share = fc.key ? kKeyShare : 1.0f;
    const float other_share = (finer ? float(ratio) : 1.0f) * uniform;
    Image<float>& share = fc.work->view_share;
    ensure_size(share, fc.ids.width, fc.ids.height);
    parallel_for(0, fc.ids.height, [&](int y0, int y1) {
        uint32_t last_id = 0;
        float last_share = other_share;  // id 0's
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < fc.ids.width; ++x) {
                const uint32_t id = fc.ids(x, y);
                if (id != last_id) {
                    last_id = id;
                    last_share =
                        id != 0 && std::any_of(fc.objects.begin(), fc.objects.end(),
                                               [&](const ObjectMotion& o) { return o.id == id; })
                            ? moving_share
                            : other_share;
                }
                share(x, y) = last_share;
            }
    });
    return share.view();
}

}  // namespace

void encode_depth(const FrameContext& fc, const Camera& camera, ImageView<const float> source,
                  Image<float>& out, std::vector<uint8_t>& bytes, StreamStats& stats) {
    const SequenceParams& sp = *fc.sp;
    const ModelCarry carry = fc.carry(&Picture::Models::depth);
    if (sp.depth == DepthMode::None) {
        out.clear();
        return;
    }
    const bool own_step =
        sp.depth == DepthMode::View && fc.view_step > 0.0f && fc.view_step != sp.view_step;
    const Mapping map = mapping_of(sp, own_step ? fc.view_step : sp.view_step);
    const int w = sp.width, h = sp.height;
    Image<uint32_t>& codes = fc.work->depth_codes;
    Image<uint32_t>& temporal = fc.work->temporal_codes;
    Image<uint32_t>& residuals = fc.work->depth_residuals;
    ensure_size(codes, w, h);
    ensure_size(residuals, w, h);
    {
        const StageTimer timer(stats.ms.reproject);
        temporal_codes(fc, camera, map, temporal);
    }
    const StageTimer timer(stats.ms.depth);
    if (!map.view)
        parallel_for(0, h, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y)
                for (int x = 0; x < w; ++x)
                    codes(x, y) = map.code(source.empty() ? INFINITY : source(x, y));
        });
    const std::size_t start = bytes.size();
    ByteWriter wr(bytes);
    wr.u8(uint8_t(own_step ? kOwnStep : 0));
    if (own_step) wr.f32(fc.view_step);
    const std::size_t slices_start = bytes.size();
    Image<uint32_t>& predictions = fc.work->depth_predictions;
    ensure_size(predictions, w, h);
    std::vector<SliceJob> jobs =
        slice_jobs(sp, map, codes, temporal, residuals, fc.work->depth_shows, &predictions);
    float uniform_share = 1.0f;
    const ImageView<const float> share = view_share(fc, map, camera, uniform_share);
    for (SliceJob& j : jobs) j.source = source, j.share = share, j.uniform_share = uniform_share;
    std::vector<std::vector<uint8_t>>& flags = fc.work->slice_flags;
    flags.resize(std::size_t(sp.slices));
    encode_slices(sp.slices, fc.work->slice_bytes, bytes, [&](int s, std::vector<uint8_t>& b) {
        encode_slice(jobs[s], carry, s, b, flags[s]);
    });
    // A frame whose every code is its temporal prediction needs only the flag.
    bool all_predicted = !temporal.empty();
    for (std::size_t i = 0; all_predicted && i < codes.pixel_count(); ++i)
        all_predicted = codes.data()[i] == temporal.data()[i];
    if (all_predicted) {
        carry.pass_on(sp.slices);  // no slice is coded
        bytes.resize(slices_start);
        bytes[start] |= kAllPredicted;
        stats.depth_zero_blocks +=
            std::size_t((w + kBlock - 1) / kBlock) * ((h + kBlock - 1) / kBlock);
    } else {
        for (const SliceJob& j : jobs) {
            stats.depth_zero_blocks += j.zero_blocks;
            stats.depth_plane_blocks += j.plane_blocks;
            stats.depth_parts += j.bits;
        }
    }
    stats.depth_bits += 8 * (bytes.size() - start);
    depth_from_codes(map, codes, out);
}

Status decode_depth(const FrameContext& fc, const Camera& camera, std::span<const uint8_t> in,
                    Image<float>& out, StreamStats& stats) {
    const SequenceParams& sp = *fc.sp;
    const ModelCarry carry = fc.carry(&Picture::Models::depth);
    if (sp.depth == DepthMode::None) {
        if (!in.empty()) return Status::error("depth section: present in a stream without depth");
        out.clear();
        return {};
    }
    ByteReader r(in, "depth section");
    const uint8_t flags = r.u8();
    if (!r.ok()) return Status::error(r.error());
    if ((flags & ~(kAllPredicted | kOwnStep)) ||
        ((flags & kOwnStep) && sp.depth != DepthMode::View))
        return Status::error("depth section: unknown flags " + std::to_string(flags));
    float step = sp.view_step;
    if (flags & kOwnStep) {
        step = r.f32();
        if (!r.ok()) return Status::error(r.error());
        if (!(step >= kMinViewStep && step <= kMaxViewStep))
            return Status::error("depth section: 1/z step " + std::to_string(step) +
                                 " outside 1e-12..1e6");
    }
    const Mapping map = mapping_of(sp, step);
    const int w = sp.width, h = sp.height;
    Image<uint32_t>& codes = fc.work->depth_codes;
    Image<uint32_t>& temporal = fc.work->temporal_codes;
    Image<uint32_t>& residuals = fc.work->depth_residuals;
    ensure_size(codes, w, h);
    ensure_size(residuals, w, h);
    {
        const StageTimer timer(stats.ms.reproject);
        temporal_codes(fc, camera, map, temporal);
    }
    const StageTimer timer(stats.ms.depth);
    if (flags & kAllPredicted) {
        if (temporal.empty())
            return Status::error("depth section: predicted from a reference on a key frame");
        if (r.remaining()) return Status::error("depth section: bytes after an all-predicted flag");
        for (std::size_t i = 0; i < codes.pixel_count(); ++i) {
            const uint32_t t = temporal.data()[i];
            codes.data()[i] = t == kNoPrediction ? map.empty() : t;
        }
        stats.depth_zero_blocks +=
            std::size_t((w + kBlock - 1) / kBlock) * ((h + kBlock - 1) / kBlock);
    } else {
        std::vector<std::span<const uint8_t>> slices;
        if (!read_slices(r, sp.slices, slices)) return Status::error(r.error());
        std::vector<SliceJob> jobs =
            slice_jobs(sp, map, codes, temporal, residuals, fc.work->depth_shows);
        REPRISE_TRY(
            decode_slices(slices, "depth section", [&](int s, std::span<const uint8_t> bytes) {
                return decode_slice(jobs[s], carry, s, bytes);
            }));
        for (const SliceJob& j : jobs) {
            stats.depth_zero_blocks += j.zero_blocks;
            stats.depth_plane_blocks += j.plane_blocks;
        }
    }
    stats.depth_bits += 8 * in.size();
    depth_from_codes(map, codes, out);
    return {};
}

}  // namespace reprise::codec
