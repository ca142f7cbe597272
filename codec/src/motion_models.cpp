// Motion within a bound: per 16x16 macroblock a quadtree down to 4x4 cells. A leaf says "the
// cameras explain it" (zero), "the neighbour's model goes on here" (merge), "a rigid object's
// motion", "a new affine model", or, for a 4x4 cell only, what each pixel is. Every decoded pixel
// lies within motion_error px of the renderer's motion (docs/bitstream.md), so a rigid or smoothly
// deformed object costs a few models instead of a residual per pixel.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <type_traits>

#include "internal.hpp"
#include "kernels.hpp"
#include "motion_models.hpp"
#include "slices.hpp"

namespace reprise::codec {

namespace {

constexpr int kUnit = 512;                          // model values in 1/512 px
constexpr int kOffsetStep = 8;                      // a new model's offset in 1/64 px
constexpr int64_t kMaxValue = int64_t(1) << 30;     // 2M px
constexpr int64_t kMaxGradient = int64_t(1) << 16;  // 128 px per px
constexpr int64_t kMaxSteps = int64_t(1) << 24;     // a pixel's own value, from its prediction
constexpr int kLevels = 3;                          // nodes of 16, 8 and 4 pixels

enum PixelKind : uint8_t { kZeroPixel = 0, kModelPixel = 1, kOwnPixel = 2 };

inline bool finite(glm::vec2 v) { return std::isfinite(v.x) && std::isfinite(v.y); }
inline glm::vec2 usable_base(glm::vec2 base) { return finite(base) ? base : glm::vec2(0.0f); }

// What a pixel decodes to from a value in 1/512 px added to the camera motion.
inline glm::vec2 model_output(glm::vec2 base, int64_t vx, int64_t vy) {
    return usable_base(base) + glm::vec2(float(vx), float(vy)) * (1.0f / kUnit);
}

inline bool within(glm::vec2 source, glm::vec2 decoded, float bound) {
    if (!finite(source) || !finite(decoded))
        return std::isnan(source.x) && std::isnan(decoded.x);  // NaN both ways needs nothing
    const glm::vec2 d = decoded - source;
    return d.x * d.x + d.y * d.y <= bound * bound;
}

// Rounded half up and clamped to +-limit (NaN gives 0).
inline int64_t clamped_round(double v, int64_t limit) {
    if (!(std::abs(v) <= double(limit))) return std::isnan(v) ? 0 : (v < 0 ? -limit : limit);
    return int64_t(std::floor(v + 0.5));
}

struct Models {
    BitModel zero[kLevels][3][3];  // [level][left and above cells not zero][edge_class]
    BitModel merge[kLevels][3];    // [level][edge_class], as split and object
    BitModel which;
    BitModel split[kLevels - 1][3];
    BitModel own_cell;
    BitModel pixel_zero[16], pixel_model[16], pixel_which[2], invalid;  // [pixel_context]
    BitModel object[kLevels][3], leaf_object, object_index[2 * kMaxObjects];
    IntModel<20> offset[2], gradient[4], pixel[2];
};

struct Job {
    const SequenceParams* sp;
    int y0, y1;
    float bound;
    int64_t step;  // of a pixel's own value
    ImageView<const float> depth;
    ImageView<const glm::vec2> base, source;  // source: encoder only
    ImageView<const uint32_t> ids;            // encoder only
    std::span<const ObjectField> fields;
    ImageView<const uint32_t> predicted;  // may be empty
    ImageView<glm::vec2> out;
    ImageView<uint32_t> owner;  // may be empty
    MotionModelScratch* scratch;
    const ModelCarry* carry;
    int slice;
    std::size_t pixels = 0, models = 0, own_pixels = 0, object_nodes = 0;
    StreamStats::MotionBits bits;  // encoder

    int width() const { return sp->width; }
    MotionCell* cell(int x, int y) const {
        if (x < 0 || y < y0) return nullptr;
        return &scratch->cells[std::size_t(y / 4) * scratch->cell_columns + x / 4];
    }
    uint8_t& kind(int x, int y) const { return scratch->kinds[std::size_t(y) * width() + x]; }
    uint8_t& which(int x, int y) const { return scratch->which[std::size_t(y) * width() + x]; }
    glm::ivec2& value(int x, int y) const { return scratch->values[std::size_t(y) * width() + x]; }
    const MotionModel* candidate(int x, int y) const {
        const MotionCell* c = cell(x, y);
        return c && c->has_model ? &c->model : nullptr;
    }
    // What model m decodes pixel (x, y) to, and the value (1/512 px over the camera motion)
    // neighbours predict from.
    glm::vec2 output(const MotionModel& m, int x, int y) const;
    glm::ivec2 model_value(const MotionModel& m, int x, int y) const;
    // m as an affine model at (x, y), what a new model is predicted from: an object's value there,
    // no gradient.
    MotionModel prediction(const MotionModel& m, int x, int y) const;
    // The object of the pixel's id (encoder), else the cameras' field when there is one, or -1.
    int object_of(int x, int y) const {
        const uint32_t id = ids(x, y);
        if (id == last_id && last_object >= -1) return last_object;  // ids come in runs
        last_id = id, last_object = -1;
        for (std::size_t k = 0; k < fields.size() && last_object < 0; ++k)
            if (fields[k].id == id) last_object = int(k);
        if (last_object < 0 && !fields.empty() && fields.back().id == 0)
            last_object = int(fields.size()) - 1;
        return last_object;
    }
    mutable uint32_t last_id = 0;
    mutable int last_object = -2;  // -2: none looked up yet
    // The owners of `count` pixels from (x, y) that took model m (nullptr: their base).
    void set_owners(int x, int y, int count, const MotionModel* m) const {
        if (owner.empty()) return;
        uint32_t* row = &owner(x, y);
        if (m)
            std::fill_n(row, count, m->object >= 0 ? fields[std::size_t(m->object)].id : 0u);
        else if (predicted.empty())
            std::fill_n(row, count, 0u);
        else
            std::copy_n(&predicted(x, y), count, row);
    }
};

// A decoded value as neighbours predict from it (clamped: prediction needs no more).
inline glm::ivec2 kept(int64_t vx, int64_t vy) {
    return {int(std::clamp(vx, -kMaxValue, kMaxValue)), int(std::clamp(vy, -kMaxValue, kMaxValue))};
}

// A pixel's own value is a multiple of this step (1/512 px) from its prediction: at most half a
// step per component, so within the bound.
glm::vec2 Job::output(const MotionModel& m, int x, int y) const {
    if (m.object >= 0) return fields[std::size_t(m.object)].at(x, y);
    return model_output(base(x, y), m.value_x(x, y), m.value_y(x, y));
}

glm::ivec2 Job::model_value(const MotionModel& m, int x, int y) const {
    if (m.object < 0) return kept(m.value_x(x, y), m.value_y(x, y));
    const glm::vec2 v = (output(m, x, y) - usable_base(base(x, y))) * float(kUnit);
    if (!finite(v)) return {0, 0};
    return kept(clamped_round(v.x, kMaxValue), clamped_round(v.y, kMaxValue));
}

MotionModel Job::prediction(const MotionModel& m, int x, int y) const {
    if (m.object < 0) return m;
    const glm::ivec2 v = model_value(m, x, y);
    MotionModel p;
    p.ax = v.x, p.ay = v.y, p.x0 = x, p.y0 = y;
    return p;
}

inline int64_t own_step(float bound) { return int64_t(std::floor(double(bound) * 512.0 * 1.38)); }

inline bool same(const MotionModel& a, const MotionModel& b) {
    return a.object == b.object && a.ax == b.ax && a.ay == b.ay && a.gxx == b.gxx &&
           a.gxy == b.gxy && a.gyx == b.gyx && a.gyy == b.gyy && a.x0 == b.x0 && a.y0 == b.y0;
}

struct Node {
    int x, y, w, h;
};

// Least squares of (source - camera motion) over the node as an affine field, quantised, the
// offset coded relative to `pred`; false when a pixel is not finite or the range is exceeded.
bool fit_model(const Job& j, const Node& n, const MotionModel& pred, MotionModel& m) {
    const double cx = n.x + (n.w - 1) * 0.5, cy = n.y + (n.h - 1) * 0.5;
    double mean[2] = {0, 0}, gx[2] = {0, 0}, gy[2] = {0, 0}, suu = 0, svv = 0;
    for (int y = n.y; y < n.y + n.h; ++y)
        for (int x = n.x; x < n.x + n.w; ++x) {
            const glm::vec2 s = j.source(x, y);
            if (!finite(s)) return false;
            const glm::vec2 d = (s - usable_base(j.base(x, y))) * float(kUnit);
            const double u = x - cx, v = y - cy;
            mean[0] += d.x, mean[1] += d.y;
            gx[0] += u * d.x, gx[1] += u * d.y;
            gy[0] += v * d.x, gy[1] += v * d.y;
            suu += u * u, svv += v * v;
        }
    const double count = double(n.w) * n.h;
    auto gradient = [](double s, double norm) {
        return norm > 0 ? clamped_round(s / norm, kMaxGradient) : int64_t(0);
    };
    m.gxx = gradient(gx[0], suu), m.gxy = gradient(gy[0], svv);
    m.gyx = gradient(gx[1], suu), m.gyy = gradient(gy[1], svv);
    m.x0 = n.x, m.y0 = n.y;
    const double ax = mean[0] / count - m.gxx * (cx - n.x) - m.gxy * (cy - n.y);
    const double ay = mean[1] / count - m.gyx * (cx - n.x) - m.gyy * (cy - n.y);
    if (!(std::abs(ax) < double(kMaxValue) && std::abs(ay) < double(kMaxValue))) return false;
    const int64_t px = pred.value_x(n.x, n.y), py = pred.value_y(n.x, n.y);
    m.ax = px + kOffsetStep * clamped_round((ax - double(px)) / kOffsetStep, 2 * kMaxValue);
    m.ay = py + kOffsetStep * clamped_round((ay - double(py)) / kOffsetStep, 2 * kMaxValue);
    return std::abs(m.ax) <= kMaxValue && std::abs(m.ay) <= kMaxValue;
}

bool model_fits(const Job& j, const Node& n, const MotionModel& m) {
    if (m.object >= 0) {  // inside the object's field: its rows against the source's
        const ObjectField& f = j.fields[std::size_t(m.object)];
        const int c = n.x - f.x0, r = n.y - f.y0;
        if (c >= 0 && r >= 0 && c + n.w <= f.motion.width() && r + n.h <= f.motion.height()) {
            for (int y = 0; y < n.h; ++y)
                if (!motion_within_row(
                        {&j.source(n.x, n.y + y), &f.motion(c, r + y), n.w, j.bound}))
                    return false;
            return true;
        }
    }
    for (int y = n.y; y < n.y + n.h; ++y)
        for (int x = n.x; x < n.x + n.w; ++x)
            if (!within(j.source(x, y), j.output(m, x, y), j.bound)) return false;
    return true;
}

bool zero_fits(const Job& j, const Node& n) {
    for (int y = n.y; y < n.y + n.h; ++y)
        if (!motion_within_row({&j.source(n.x, y), &j.base(n.x, y), n.w, j.bound})) return false;
    return true;
}

void set_cells(const Job& j, const Node& n, const MotionModel* model, bool zero) {
    for (int y = n.y; y < n.y + n.h; y += 4)
        for (int x = n.x; x < n.x + n.w; x += 4) {
            MotionCell& c = *j.cell(x, y);
            c.has_model = model != nullptr;
            if (model) c.model = *model;
            c.zero = zero;
        }
}

void apply_zero(Job& j, const Node& n) {
    // Row by row as copies and fills (a node is a tile: the rows' loads miss the caches, and
    // pixel by pixel each waited on the last through the byte stores' aliasing).
    for (int y = n.y; y < n.y + n.h; ++y) {
        std::copy_n(&j.base(n.x, y), n.w, &j.out(n.x, y));
        j.set_owners(n.x, y, n.w, nullptr);
        std::fill_n(&j.kind(n.x, y), n.w, uint8_t(kZeroPixel));
        std::fill_n(&j.value(n.x, y), n.w, glm::ivec2(0));
    }
    set_cells(j, n, nullptr, true);
}

void apply_model(Job& j, const Node& n, const MotionModel& m) {
    for (int y = n.y; y < n.y + n.h; ++y) {
        j.set_owners(n.x, y, n.w, &m);
        for (int x = n.x; x < n.x + n.w; ++x) {
            j.out(x, y) = j.output(m, x, y);
            j.kind(x, y) = kModelPixel;
            j.value(x, y) = j.model_value(m, x, y);
        }
    }
    j.pixels += std::size_t(n.w) * n.h;
    set_cells(j, n, &m, false);
}

// Two decoded depths on different surfaces: a relative step over 1/64, or one is no surface.
inline bool is_surface(float z) { return z > 0.0f && z < std::numeric_limits<float>::infinity(); }
inline bool depth_step(float a, float b) {
    if (!is_surface(a) || !is_surface(b)) return is_surface(a) != is_surface(b);
    return std::abs(a - b) > (1.0f / 64.0f) * std::min(a, b);
}

// A pixel's context: for the left and the above neighbour, whether it took the camera's motion,
// and whether a step in depth or between predicted owners lies between them (version 20).
inline int pixel_context(const Job& j, int x, int y) {
    auto state = [&](int nx, int ny) {
        return (j.kind(nx, ny) != kZeroPixel) +
               2 * ((!j.depth.empty() && depth_step(j.depth(nx, ny), j.depth(x, y))) ||
                    (!j.predicted.empty() && j.predicted(nx, ny) != j.predicted(x, y)));
    };
    return (x > 0 ? state(x - 1, y) : 0) + 4 * (y > j.y0 ? state(x, y - 1) : 0);
}

// Version 20: per 4x4 cell, whether a pixel of it and its right or lower neighbour lie on two
// surfaces (bit 0), or on one surface that the reference says two owners share (bit 1: where an
// object touches what it stands on, the motions differ without a step in depth).
constexpr uint8_t kDepthEdge = 1, kOwnerEdge = 2;
void find_edges(const SequenceParams& sp, ImageView<const float> depth,
                ImageView<const uint32_t> predicted, MotionModelScratch& scratch) {
    const int rows = (sp.height + 3) / 4;
    scratch.edges.assign(std::size_t(scratch.cell_columns) * rows, 0);
    if (depth.empty()) return;
    parallel_for(0, rows, [&](int r0, int r1) {
        for (int y = 4 * r0; y < std::min(sp.height, 4 * r1); ++y) {
            const float* z = depth.row(y);
            const float* below = y + 1 < sp.height ? depth.row(y + 1) : nullptr;
            const uint32_t* o = predicted.empty() ? nullptr : predicted.row(y);
            const uint32_t* o_below = o && below ? predicted.row(y + 1) : nullptr;
            uint8_t* cells = &scratch.edges[std::size_t(y / 4) * scratch.cell_columns];
            auto edge = [](bool step, bool owners) {
                return step ? kDepthEdge : owners ? kOwnerEdge : uint8_t(0);
            };
            for (int x = 0; x < sp.width; ++x) {
                if (x + 1 < sp.width)
                    cells[x / 4] |= edge(depth_step(z[x], z[x + 1]), o && o[x] != o[x + 1]);
                if (below)
                    cells[x / 4] |= edge(depth_step(z[x], below[x]), o_below && o[x] != o_below[x]);
            }
        }
    });
}

// A node's class for its flags: no edge, steps in depth only, an edge between owners.
int edge_class(const Job& j, const Node& n) {
    uint8_t e = 0;
    for (int cy = n.y / 4; cy < (n.y + n.h + 3) / 4; ++cy)
        for (int cx = n.x / 4; cx < (n.x + n.w + 3) / 4; ++cx)
            e |= j.scratch->edges[std::size_t(cy) * j.scratch->cell_columns + cx];
    return e & kOwnerEdge ? 2 : e;
}

// A 4x4 cell pixel by pixel: the camera's motion, one of the node's candidate models, or its own
// value (predicted from its neighbours).
template <bool Encode, class Coder>
bool code_pixels(Job& j, Models& m, const Node& n, const MotionModel* const (&cands)[2],
                 Coder& rc) {
    for (int y = n.y; y < n.y + n.h; ++y)
        for (int x = n.x; x < n.x + n.w; ++x) {
            const int ctx = pixel_context(j, x, y);
            const glm::vec2 base = j.base(x, y);
            PixelKind kind = kOwnPixel;
            int which = 0;
            const int which_ctx = x > n.x && j.kind(x - 1, y) == kModelPixel && j.which(x - 1, y);
            if constexpr (Encode) {
                const glm::vec2 s = j.source(x, y);
                if (within(s, base, j.bound)) {
                    kind = kZeroPixel;
                } else {
                    for (int k = 0; k < 2 && kind == kOwnPixel; ++k)
                        if (cands[k] && within(s, j.output(*cands[k], x, y), j.bound))
                            kind = kModelPixel, which = k;
                }
                rc.bit(m.pixel_zero[ctx], kind == kZeroPixel);
                if (kind != kZeroPixel && cands[0]) {
                    rc.bit(m.pixel_model[ctx], kind == kModelPixel);
                    if (kind == kModelPixel && cands[1]) rc.bit(m.pixel_which[which_ctx], which);
                }
            } else {
                if (rc.bit(m.pixel_zero[ctx])) {
                    kind = kZeroPixel;
                } else if (cands[0] && rc.bit(m.pixel_model[ctx])) {
                    kind = kModelPixel;
                    which = cands[1] ? rc.bit(m.pixel_which[which_ctx]) : 0;
                }
            }
            j.which(x, y) = uint8_t(which);
            glm::vec2 out = base;
            if (kind == kModelPixel) out = j.output(*cands[which], x, y);
            glm::ivec2 value =
                kind == kModelPixel ? j.model_value(*cands[which], x, y) : glm::ivec2(0);
            if (kind == kOwnPixel) {
                // Predicted like a smooth field: the left pixel's value, else the above one's
                // (when they are not the camera's), else the candidate's.
                glm::ivec2 pred = cands[0] ? j.model_value(*cands[0], x, y) : glm::ivec2(0);
                if (x > 0 && j.kind(x - 1, y) != kZeroPixel)
                    pred = j.value(x - 1, y);
                else if (y > j.y0 && j.kind(x, y - 1) != kZeroPixel)
                    pred = j.value(x, y - 1);
                bool invalid = false;
                int64_t kx = 0, ky = 0;
                if constexpr (Encode) {
                    const glm::vec2 s = j.source(x, y);
                    invalid = !finite(s);
                    rc.bit(m.invalid, invalid);
                    if (!invalid) {
                        const glm::vec2 d = (s - usable_base(base)) * float(kUnit);
                        kx = clamped_round((double(d.x) - pred.x) / double(j.step), kMaxSteps);
                        ky = clamped_round((double(d.y) - pred.y) / double(j.step), kMaxSteps);
                        encode_int(rc, m.pixel[0], kx);
                        encode_int(rc, m.pixel[1], ky);
                    }
                } else {
                    invalid = rc.bit(m.invalid);
                    if (!invalid &&
                        (!decode_int(rc, m.pixel[0], kx) || !decode_int(rc, m.pixel[1], ky) ||
                         std::abs(kx) > kMaxSteps || std::abs(ky) > kMaxSteps))
                        return false;
                }
                const int64_t vx = pred.x + kx * j.step, vy = pred.y + ky * j.step;
                out = invalid ? glm::vec2(std::numeric_limits<float>::quiet_NaN())
                              : model_output(base, vx, vy);
                value = invalid ? glm::ivec2(0) : kept(vx, vy);
                ++j.own_pixels;
            }
            j.out(x, y) = out;
            j.set_owners(x, y, 1, kind == kModelPixel ? cands[which] : nullptr);
            j.kind(x, y) = kind;
            j.value(x, y) = value;
            j.pixels += kind != kZeroPixel;
        }
    set_cells(j, n, cands[0], false);
    return true;
}

// An object index below `count`, bit by bit from the top through a tree of models; false when
// the decoded index is not below count.
template <class Coder>
bool code_object_index(Models& m, int count, int& index, Coder& rc) {
    int bits = 0;
    while ((1 << bits) < count) ++bits;
    int node = 1, value = 0;
    for (int b = bits - 1; b >= 0; --b) {
        int bit = 0;
        if constexpr (std::is_same_v<Coder, RangeEncoder>) {
            bit = (index >> b) & 1;
            rc.bit(m.object_index[node], bit);
        } else {
            bit = rc.bit(m.object_index[node]);
        }
        value = value * 2 + bit;
        node = node * 2 + bit;
    }
    index = value;
    return value < count;
}

// The object that fits the whole node (encoder): the objects of the node's ids in turn.
int fitting_object(const Job& j, const Node& n) {
    int tried[2] = {-1, -1};
    for (int y = n.y; y < n.y + n.h; ++y)
        for (int x = n.x; x < n.x + n.w; ++x) {
            const int k = j.object_of(x, y);
            if (k < 0 || k == tried[0] || k == tried[1]) continue;
            MotionModel object;
            object.object = k;
            if (model_fits(j, n, object)) return k;
            if (tried[0] >= 0 && tried[1] >= 0) return -1;
            tried[tried[0] >= 0] = k;
        }
    return -1;
}

// The object worth adding to a 4x4 cell's candidates (encoder): the one that gives the most of
// its pixels that neither the cameras nor the candidates give, if any.
int leaf_object(const Job& j, const Node& n, const MotionModel* const (&cands)[2]) {
    int best = -1, best_count = 0;
    for (int y = n.y; y < n.y + n.h; ++y)
        for (int x = n.x; x < n.x + n.w; ++x) {
            const int k = j.object_of(x, y);
            if (k < 0 || k == best) continue;
            bool offered = false;
            for (const MotionModel* c : cands) offered = offered || (c && c->object == k);
            if (offered) continue;
            MotionModel object;
            object.object = k;
            int count = 0;
            for (int yy = n.y; yy < n.y + n.h; ++yy)
                for (int xx = n.x; xx < n.x + n.w; ++xx) {
                    const glm::vec2 s = j.source(xx, yy);
                    if (within(s, j.base(xx, yy), j.bound)) continue;
                    bool given = false;
                    for (const MotionModel* c : cands)
                        given = given || (c && within(s, j.output(*c, xx, yy), j.bound));
                    count += !given && within(s, j.output(object, xx, yy), j.bound);
                }
            if (count > best_count) best = k, best_count = count;
        }
    return best;
}

template <bool Encode, class Coder>
bool code_new_model(Job& j, Models& m, const Node& n, const MotionModel& pred, MotionModel& model,
                    Coder& rc) {
    const int64_t px = pred.value_x(n.x, n.y), py = pred.value_y(n.x, n.y);
    int64_t d[6];
    if constexpr (Encode) {
        d[0] = (model.ax - px) / kOffsetStep, d[1] = (model.ay - py) / kOffsetStep;
        d[2] = model.gxx - pred.gxx, d[3] = model.gxy - pred.gxy;
        d[4] = model.gyx - pred.gyx, d[5] = model.gyy - pred.gyy;
        encode_int(rc, m.offset[0], d[0]);
        encode_int(rc, m.offset[1], d[1]);
        for (int k = 0; k < 4; ++k) encode_int(rc, m.gradient[k], d[2 + k]);
    } else {
        if (!decode_int(rc, m.offset[0], d[0]) || !decode_int(rc, m.offset[1], d[1])) return false;
        for (int k = 0; k < 4; ++k)
            if (!decode_int(rc, m.gradient[k], d[2 + k])) return false;
        model.ax = px + d[0] * kOffsetStep, model.ay = py + d[1] * kOffsetStep;
        model.gxx = pred.gxx + d[2], model.gxy = pred.gxy + d[3];
        model.gyx = pred.gyx + d[4], model.gyy = pred.gyy + d[5];
        model.x0 = n.x, model.y0 = n.y;
        if (std::abs(model.ax) > kMaxValue || std::abs(model.ay) > kMaxValue) return false;
        for (int64_t g : {model.gxx, model.gxy, model.gyx, model.gyy})
            if (std::abs(g) > kMaxGradient) return false;
    }
    ++j.models;
    return true;
}

template <bool Encode, class Coder>
bool code_node(Job& j, Models& m, Node n, int level, Coder& rc) {
    n.w = std::min(n.w, j.width() - n.x);
    n.h = std::min(n.h, j.y1 - n.y);
    if (n.w <= 0 || n.h <= 0) return true;
    const MotionCell *left = j.cell(n.x - 1, n.y), *top = j.cell(n.x, n.y - 1);
    const int zero_ctx = (left && !left->zero) + (top && !top->zero);
    const int edge = edge_class(j, n);
    bool zero = false;
    if constexpr (Encode) {
        rc.tally_into(&j.bits.tree);
        zero = zero_fits(j, n);
        rc.bit(m.zero[level][zero_ctx][edge], zero);
    } else {
        zero = rc.bit(m.zero[level][zero_ctx][edge]);
    }
    if (zero) {
        apply_zero(j, n);
        return true;
    }
    const MotionModel* cands[2] = {j.candidate(n.x - 1, n.y), j.candidate(n.x, n.y - 1)};
    if (!cands[0]) std::swap(cands[0], cands[1]);
    if (cands[1] && same(*cands[0], *cands[1])) cands[1] = nullptr;
    if (cands[0]) {
        int chosen = -1;
        if constexpr (Encode) {
            for (int k = 0; k < 2 && chosen < 0; ++k)
                if (cands[k] && model_fits(j, n, *cands[k])) chosen = k;
            rc.bit(m.merge[level][edge], chosen >= 0);
            if (chosen >= 0 && cands[1]) rc.bit(m.which, chosen);
        } else if (rc.bit(m.merge[level][edge])) {
            chosen = cands[1] ? rc.bit(m.which) : 0;
        }
        if (chosen >= 0) {
            const MotionModel merged = *cands[chosen];  // a copy: set_cells overwrites the source
            apply_model(j, n, merged);
            return true;
        }
    }
    if (!j.fields.empty()) {
        MotionModel object;
        if constexpr (Encode) {
            object.object = fitting_object(j, n);
            rc.bit(m.object[level][edge], object.object >= 0);
            if (object.object >= 0) code_object_index(m, int(j.fields.size()), object.object, rc);
        } else if (rc.bit(m.object[level][edge]) &&
                   !code_object_index(m, int(j.fields.size()), object.object, rc)) {
            return false;
        }
        if (object.object >= 0) {
            apply_model(j, n, object);
            ++j.object_nodes;
            return true;
        }
    }
    const MotionModel none;
    const MotionModel pred = cands[0] ? j.prediction(*cands[0], n.x, n.y) : none;
    MotionModel model;
    bool fits = false;
    if constexpr (Encode) fits = fit_model(j, n, pred, model) && model_fits(j, n, model);
    if (level < kLevels - 1) {
        if constexpr (Encode)
            rc.bit(m.split[level][edge], !fits);
        else
            fits = !rc.bit(m.split[level][edge]);
        if (!fits) {
            const int half = (kMb >> level) / 2;
            for (int k = 0; k < 4; ++k)
                if (!code_node<Encode>(j, m,
                                       {n.x + (k & 1) * half, n.y + (k >> 1) * half, half, half},
                                       level + 1, rc))
                    return false;
            return true;
        }
    } else {
        if constexpr (Encode)
            rc.bit(m.own_cell, !fits);
        else
            fits = !rc.bit(m.own_cell);
        if (!fits) {
            // An object the neighbours do not offer may join the candidates.
            MotionModel object;
            if (!j.fields.empty()) {
                if constexpr (Encode) {
                    object.object = leaf_object(j, n, cands);
                    rc.bit(m.leaf_object, object.object >= 0);
                    if (object.object >= 0)
                        code_object_index(m, int(j.fields.size()), object.object, rc);
                } else if (rc.bit(m.leaf_object) &&
                           !code_object_index(m, int(j.fields.size()), object.object, rc)) {
                    return false;
                }
                if (object.object >= 0) cands[cands[0] ? 1 : 0] = &object;
            }
            if constexpr (Encode) rc.tally_into(&j.bits.pixels);
            return code_pixels<Encode>(j, m, n, cands, rc);
        }
    }
    if constexpr (Encode) rc.tally_into(&j.bits.models);
    if (!code_new_model<Encode>(j, m, n, pred, model, rc)) return false;
    apply_model(j, n, model);
    return true;
}

template <bool Encode, class Coder>
bool code_slice(Job& j, Coder& rc) {
    Models m;
    j.carry->load(j.slice, m);
    for (int y = j.y0; y < j.y1; y += kMb) {
        for (int x = 0; x < j.width(); x += kMb)
            if (!code_node<Encode>(j, m, {x, y, kMb, kMb}, 0, rc)) return false;
        if constexpr (!Encode) {
            if (rc.overrun() > 8) return false;
        }
    }
    j.carry->save(j.slice, m);
    return true;
}

std::vector<Job> slice_jobs(const SequenceParams& sp, ImageView<const float> depth,
                            ImageView<const glm::vec2> base, ImageView<const glm::vec2> source,
                            ImageView<const uint32_t> ids, std::span<const ObjectField> fields,
                            ImageView<const uint32_t> predicted, ImageView<glm::vec2> out,
                            ImageView<uint32_t> owner, MotionModelScratch& scratch,
                            const ModelCarry& carry) {
    scratch.cell_columns = (sp.width + 3) / 4;
    scratch.cells.assign(std::size_t(scratch.cell_columns) * ((sp.height + 3) / 4), {});
    scratch.kinds.resize(std::size_t(sp.width) * sp.height);
    scratch.values.resize(std::size_t(sp.width) * sp.height);
    scratch.which.resize(std::size_t(sp.width) * sp.height);
    find_edges(sp, depth, predicted, scratch);
    std::vector<Job> jobs;
    for (int s = 0; s < sp.slices; ++s) {
        const int y0 = std::min(sp.height, sp.slice_begin(s) * kMb);
        const int y1 = std::min(sp.height, sp.slice_begin(s + 1) * kMb);
        jobs.push_back({&sp, y0, y1, sp.motion_error, own_step(sp.motion_error), depth, base,
                        source, ids, fields, predicted, out, owner, &scratch, &carry, s});
    }
    return jobs;
}

void add_counts(const std::vector<Job>& jobs, StreamStats& stats) {
    for (const Job& j : jobs) {
        stats.motion_residual_pixels += j.pixels;
        stats.motion_models += j.models;
        stats.motion_own_pixels += j.own_pixels;
        stats.motion_parts += j.bits;
    }
}

}  // namespace

bool motion_within_row_reference(const MotionWithinRow& r, int x_begin, int x_end) {
    for (int x = x_begin; x < x_end; ++x)
        if (!within(r.source[x], r.decoded[x], r.bound)) return false;
    return true;
}

bool motion_within_bound(ImageView<const glm::vec2> source, ImageView<const glm::vec2> base, int y,
                         float bound) {
    return motion_within_row({source.row(y), base.row(y), source.width, bound});
}

void encode_motion_models(const SequenceParams& sp, ImageView<const float> depth,
                          ImageView<const glm::vec2> base, ImageView<const glm::vec2> source,
                          ImageView<const uint32_t> ids, std::span<const ObjectField> fields,
                          ImageView<const uint32_t> predicted, ImageView<glm::vec2> out,
                          ImageView<uint32_t> owner, MotionModelScratch& scratch,
                          const ModelCarry& carry, std::vector<std::vector<uint8_t>>& slice_bytes,
                          std::vector<uint8_t>& bytes, StreamStats& stats) {
    std::vector<Job> jobs =
        slice_jobs(sp, depth, base, source, ids, fields, predicted, out, owner, scratch, carry);
    encode_slices(sp.slices, slice_bytes, bytes, [&](int s, std::vector<uint8_t>& b) {
        RangeEncoder rc(b);
        code_slice<true>(jobs[s], rc);
        rc.finish();
    });
    add_counts(jobs, stats);
}

Status decode_motion_models(const SequenceParams& sp, ImageView<const float> depth,
                            ImageView<const glm::vec2> base, std::span<const ObjectField> fields,
                            ImageView<const uint32_t> predicted,
                            const std::vector<std::span<const uint8_t>>& slices,
                            ImageView<glm::vec2> out, ImageView<uint32_t> owner,
                            MotionModelScratch& scratch, const ModelCarry& carry,
                            StreamStats& stats) {
    std::vector<Job> jobs =
        slice_jobs(sp, depth, base, {}, {}, fields, predicted, out, owner, scratch, carry);
    REPRISE_TRY(decode_slices(slices, "motion section", [&](int s, std::span<const uint8_t> b) {
        RangeDecoder rc(b);
        return code_slice<false>(jobs[s], rc);
    }));
    add_counts(jobs, stats);
    return {};
}

}  // namespace reprise::codec
