// Rigid object motion: per object id a Levenberg-Marquardt fit (least_squares.hpp) of a rotation
// about the object's centroid and a translation to the reprojection error of its pixels' motion,
// with rounds of trimming that drop what does not move with the object (skinned parts, shadows).
#include "object_motion.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <map>
#include <mutex>

#include <glm/gtc/quaternion.hpp>

#include "internal.hpp"
#include "kernels.hpp"
#include "least_squares.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::codec {

namespace {

constexpr int kMinPixels = 16;    // pixels the cameras do not explain
constexpr int kMaxSamples = 300;  // per object
constexpr int kRounds = 4;
constexpr double kFloorPx = 0.05;          // the smallest trimming threshold
constexpr double kMaxArea = 4.0;           // all objects' pixels, in pictures
constexpr double kMaxTranslation = 1e20;   // decoder's sanity limit
constexpr double kQuaternionSlack = 1e-4;  // |vector part|^2 above 1 allowed by rounding

struct Sample {
    glm::dvec3 point;  // camera space in units of the object's depth, relative to its centroid
    double tx, ty;     // where the pixel was in the previous frame
};

struct RigidModel {
    glm::dmat4 clip;  // camera space -> the previous image's clip space
    glm::dvec3 centre;
    double unit, width, height;
    const std::vector<Sample>* samples;

    // The samples that `o` moves to within `bound` px of where they were.
    int explained(const ObjectMotion& o, double bound) const {
        const glm::dmat4 m = clip * o.matrix();
        int count = 0;
        for (const Sample& s : *samples) {
            const glm::dvec4 c = m * glm::dvec4((s.point + centre) * unit, 1.0);
            if (!(c.w > 1e-12)) continue;
            const double dx = (c.x / c.w + 1.0) * 0.5 * width - s.tx;
            const double dy = (1.0 - c.y / c.w) * 0.5 * height - s.ty;
            count += dx * dx + dy * dy <= bound * bound;
        }
        return count;
    }

    void residuals(const fit::Params& q, const std::vector<Sample>& s,
                   std::vector<double>& r) const {
        const glm::dmat3 rot = fit::rotation(q[0], q[1], q[2]);
        const glm::dvec3 t(q[3], q[4], q[5]);
        r.resize(2 * s.size());
        for (std::size_t i = 0; i < s.size(); ++i) {
            const glm::dvec3 y = (rot * s[i].point + centre + t) * unit;
            const glm::dvec4 c = clip * glm::dvec4(y, 1.0);
            if (!(c.w > 1e-12)) {
                r[2 * i] = r[2 * i + 1] = fit::kBehindPx;
                continue;
            }
            r[2 * i] = (c.x / c.w + 1.0) * 0.5 * width - s[i].tx;
            r[2 * i + 1] = (1.0 - c.y / c.w) * 0.5 * height - s[i].ty;
        }
    }
};

struct Candidate {
    uint32_t id = 0;
    int pixels = 0, usable = 0, unexplained = 0;
    int x0 = 1 << 30, y0 = 1 << 30, x1 = 0, y1 = 0;
    std::vector<Sample> samples;
    int seen = 0;  // usable pixels met while sampling
};

inline bool finite(glm::vec2 v) { return std::isfinite(v.x) && std::isfinite(v.y); }

inline bool explains(glm::vec2 source, glm::vec2 m, float bound) {
    const glm::vec2 d = m - source;
    return finite(d) && d.x * d.x + d.y * d.y <= bound * bound;
}

}  // namespace

ObjectPixels object_pixels_row_reference(const ObjectPixelsRow& r, int i_begin, int i_end) {
    ObjectPixels total;
    for (int i = i_begin; i < i_end; ++i) {
        const float z = r.depth[i];
        const bool usable = z > 0.0f && std::isfinite(z) && finite(r.motion[i]);
        total.usable += usable;
        total.unexplained += usable && !explains(r.motion[i], r.base[i], r.bound);
    }
    return total;
}

namespace {

// Fits one object; false when its transform explains no more samples than the cameras.
bool fit_one(const Camera& camera, Candidate& c, float bound, int width, int height,
             const ObjectMotion* previous, ObjectMotion& out) {
    std::vector<Sample>& s = c.samples;
    if (int(s.size()) < 6) return false;
    std::vector<double> depths;
    glm::dvec3 centre(0.0);
    for (const Sample& p : s) depths.push_back(-p.point.z), centre += p.point;
    const double unit = std::max(fit::median(depths), 1e-30);
    centre /= double(s.size());
    for (Sample& p : s) p.point = (p.point - centre) / unit;
    const RigidModel model{glm::dmat4(rigid_to_clip(camera, glm::dmat4(1.0))),
                           centre / unit,
                           unit,
                           double(width),
                           double(height),
                           &s};
    fit::Params q{};
    std::vector<uint8_t> inlier(s.size(), 1);
    std::vector<double> r, norms(s.size());
    for (int round = 0; round < kRounds; ++round) {
        fit::refine(model, s, inlier, 6, q);
        model.residuals(q, s, r);
        for (std::size_t i = 0; i < s.size(); ++i) norms[i] = std::hypot(r[2 * i], r[2 * i + 1]);
        const double threshold = std::max(3.0 * 1.4826 * fit::median(norms), kFloorPx);
        bool same = true;
        for (std::size_t i = 0; i < s.size(); ++i) {
            const uint8_t in = norms[i] <= threshold;
            same = same && in == inlier[i];
            inlier[i] = in;
        }
        // Settled on an exact fit: another round would refit the same samples to the same end.
        if (same && threshold <= kFloorPx) break;
    }
    for (double v : q)
        if (!std::isfinite(v)) return false;
    // X -> R (X - c) + c + t, in scene units: t' = (c + t - R c) unit.
    const glm::dmat3 rot = fit::rotation(q[0], q[1], q[2]);
    glm::dquat quat = glm::quat_cast(rot);
    if (quat.w < 0.0) quat = -quat;
    const glm::dvec3 t = (model.centre + glm::dvec3(q[3], q[4], q[5]) - rot * model.centre) * unit;
    if (!(glm::length(t) < kMaxTranslation)) return false;
    out = {.x0 = c.x0,
           .y0 = c.y0,
           .x1 = c.x1,
           .y1 = c.y1,
           .rotation = {float(quat.x), float(quat.y), float(quat.z)},
           .translation = {float(t.x), float(t.y), float(t.z)},
           .id = c.id};
    // Counted with the transform as sent; the previous frame's transform of the object goes on
    // when it explains as many samples closely (constant motion costs no parameters).
    if (previous) {
        ObjectMotion kept = *previous;
        kept.x0 = c.x0, kept.y0 = c.y0, kept.x1 = c.x1, kept.y1 = c.y1;
        if (model.explained(kept, 0.5 * bound) >= model.explained(out, 0.5 * bound)) out = kept;
    }
    const double share_unexplained = double(c.unexplained) / std::max(c.usable, 1);
    const int count = model.explained(out, bound);
    return count >= 8 && count > (1.0 - share_unexplained) * double(s.size());
}

}  // namespace

glm::dmat4 ObjectMotion::matrix() const {
    const double x = rotation[0], y = rotation[1], z = rotation[2];
    const double w = std::sqrt(std::max(0.0, 1.0 - (x * x + y * y + z * z)));
    glm::dmat4 m(1.0);
    m[0][0] = 1.0 - 2.0 * (y * y + z * z), m[0][1] = 2.0 * (x * y + w * z),
    m[0][2] = 2.0 * (x * z - w * y);
    m[1][0] = 2.0 * (x * y - w * z), m[1][1] = 1.0 - 2.0 * (x * x + z * z),
    m[1][2] = 2.0 * (y * z + w * x);
    m[2][0] = 2.0 * (x * z + w * y), m[2][1] = 2.0 * (y * z - w * x),
    m[2][2] = 1.0 - 2.0 * (x * x + y * y);
    m[3] = glm::dvec4(translation[0], translation[1], translation[2], 1.0);
    return m;
}

glm::vec2 ObjectField::at(int x, int y) const {
    const int c = x - x0, r = y - y0;
    if (c < 0 || r < 0 || c >= motion.width() || r >= motion.height())
        return glm::vec2(std::numeric_limits<float>::quiet_NaN());
    return motion(c, r);
}

std::vector<ObjectMotion> fit_object_motions(const Camera& camera, ImageView<const float> depth,
                                             ImageView<const uint32_t> ids,
                                             ImageView<const glm::vec2> motion,
                                             ImageView<const glm::vec2> base, float bound,
                                             std::span<const ObjectMotion> previous) {
    const int w = depth.width, h = depth.height;
    std::vector<ObjectMotion> objects;
    if (ids.width != w || ids.height != h || motion.width != w || motion.height != h)
        return objects;
    std::map<uint32_t, Candidate> found;
    auto usable = [&](int x, int y) {
        const float z = depth(x, y);
        return z > 0.0f && std::isfinite(z) && finite(motion(x, y));
    };
    // Counted per band of rows in parallel, merged under a lock (sums and extents: any order).
    std::mutex merging;
    parallel_for(0, h, [&](int r0, int r1) {
        std::map<uint32_t, Candidate> band;
        Candidate* last = nullptr;  // ids come in runs: one map lookup per run
        for (int y = r0; y < r1; ++y) {
            const uint32_t* id_row = ids.row(y);
            const float* z_row = depth.row(y);
            const glm::vec2 *m_row = motion.row(y), *base_row = base.row(y);
            for (int x = 0, end = 0; x < w; x = end) {
                const uint32_t id = id_row[x];
                for (end = x + 1; end < w && id_row[end] == id;) ++end;
                if (id == 0) continue;
                if (!last || last->id != id) {
                    last = &band[id];
                    last->id = id;
                }
                Candidate& c = *last;
                c.pixels += end - x;
                c.x0 = std::min(c.x0, x), c.y0 = std::min(c.y0, y);
                c.x1 = std::max(c.x1, end), c.y1 = std::max(c.y1, y + 1);
                const ObjectPixels run =
                    object_pixels_row({z_row + x, m_row + x, base_row + x, end - x, bound});
                c.usable += run.usable, c.unexplained += run.unexplained;
            }
        }
        const std::lock_guard lock(merging);
        for (const auto& [id, b] : band) {
            Candidate& c = found[id];
            c.id = id;
            c.pixels += b.pixels, c.usable += b.usable, c.unexplained += b.unexplained;
            c.x0 = std::min(c.x0, b.x0), c.y0 = std::min(c.y0, b.y0);
            c.x1 = std::max(c.x1, b.x1), c.y1 = std::max(c.y1, b.y1);
        }
    });
    std::vector<Candidate*> chosen;
    for (auto& [id, c] : found)
        if (c.unexplained >= kMinPixels) chosen.push_back(&c);
    std::stable_sort(chosen.begin(), chosen.end(), [](const Candidate* a, const Candidate* b) {
        return a->unexplained > b->unexplained;
    });
    if (chosen.size() > std::size_t(kMaxObjects)) chosen.resize(kMaxObjects);
    if (chosen.empty()) return objects;
    std::map<uint32_t, Candidate*> by_id;
    for (Candidate* c : chosen) by_id[c->id] = c;
    uint32_t last_id = 0;
    Candidate* chosen_of_last = nullptr;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const uint32_t id = ids(x, y);
            if (id == 0) continue;
            if (id != last_id) {
                const auto it = by_id.find(id);
                last_id = id;
                chosen_of_last = it == by_id.end() ? nullptr : it->second;
            }
            if (!chosen_of_last || !usable(x, y)) continue;
            Candidate& c = *chosen_of_last;
            // Evenly over the usable pixels: the k-th sample at the k * usable / kMaxSamples-th.
            const int k = int(int64_t(c.seen++) * std::min(c.usable, kMaxSamples) / c.usable);
            if (k < int(c.samples.size())) continue;
            glm::vec4 p;
            if (!unproject_pixel(camera, w, h, x, y, depth(x, y), p)) continue;
            const glm::vec2 m = motion(x, y);
            c.samples.push_back({glm::dvec3(p), x + 0.5 + m.x, y + 0.5 + m.y});
        }
    double area = 0.0;
    for (Candidate* c : chosen) {
        ObjectMotion o;
        const ObjectMotion* before = nullptr;
        for (const ObjectMotion& p : previous)
            if (p.id == c->id) before = &p;
        if (!fit_one(camera, *c, bound, w, h, before, o)) continue;
        area += double(o.x1 - o.x0) * (o.y1 - o.y0);
        if (area > kMaxArea * w * h) break;
        objects.push_back(o);
    }
    return objects;
}

void object_fields(const Camera& camera, ImageView<const float> depth,
                   std::span<const ObjectMotion> objects, std::vector<ObjectField>& fields) {
    fields.resize(objects.size());
    for (std::size_t k = 0; k < objects.size(); ++k) {
        const ObjectMotion& o = objects[k];
        ObjectField& f = fields[k];
        f.id = o.id, f.x0 = o.x0, f.y0 = o.y0;
        ensure_size(f.motion, o.x1 - o.x0, o.y1 - o.y0);
        ensure_size(f.depth, o.x1 - o.x0, o.y1 - o.y0);
        const glm::mat4 to_camera(glm::dmat4(camera.prev_view) *
                                  glm::inverse(glm::dmat4(camera.view)) * o.matrix());
        rigid_motion(camera, depth, rigid_to_clip(camera, o.matrix()), o.x0, o.y0, f.motion.view(),
                     to_camera, f.depth.view());
    }
}

bool predict_owners(std::span<const ObjectField> fields, uint32_t objects,
                    ImageView<const float> reference_depth,
                    ImageView<const uint32_t> reference_owner, ImageView<uint32_t> out) {
    const int w = out.width, h = out.height;
    parallel_for(0, h, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) std::fill(out.row(y), out.row(y) + w, 0u);
    });
    std::atomic<bool> any{false};
    for (std::size_t k = 0; k < fields.size() && k < 32; ++k) {
        const ObjectField& f = fields[k];
        if (!(objects >> k & 1) || f.id == 0 || f.depth.empty()) continue;
        parallel_for(0, f.motion.height(), [&](int r0, int r1) {
            bool found = false;
            for (int r = r0; r < r1; ++r)
                for (int c = 0; c < f.motion.width(); ++c) {
                    const int x = f.x0 + c, y = f.y0 + r;
                    const glm::vec2 m = f.motion(c, r);
                    const float z = f.depth(c, r);
                    if (out(x, y) != 0 || !finite(m) || !(z > 0.0f && std::isfinite(z))) continue;
                    // The four reference pixels around where it was.
                    const float qx = float(x) + m.x, qy = float(y) + m.y;
                    if (!(qx >= -1.0f && qy >= -1.0f && qx < float(w) && qy < float(h))) continue;
                    const int rx = int(std::floor(qx)), ry = int(std::floor(qy));
                    bool moved = false;
                    for (int dy = 0; dy < 2 && !moved; ++dy)
                        for (int dx = 0; dx < 2 && !moved; ++dx) {
                            const int sx = rx + dx, sy = ry + dy;
                            moved = sx >= 0 && sy >= 0 && sx < w && sy < h &&
                                    reference_owner(sx, sy) == f.id &&
                                    std::abs(reference_depth(sx, sy) - z) <= z * (1.0f / 16.0f);
                        }
                    if (!moved) continue;
                    out(x, y) = f.id;
                    found = true;
                }
            if (found) any.store(true, std::memory_order_relaxed);
        });
    }
    return any.load();
}

namespace {

const ObjectMotion* same_id(const std::vector<ObjectMotion>* reference, uint64_t id) {
    if (reference)
        for (const ObjectMotion& o : *reference)
            if (o.id == id) return &o;
    return nullptr;
}

// The six floats of an object in order: rotation, translation.
template <class O>
auto floats(O& o) {
    return std::array{&o.rotation[0],    &o.rotation[1],    &o.rotation[2],
                      &o.translation[0], &o.translation[1], &o.translation[2]};
}

}  // namespace

void write_objects(std::span<const ObjectMotion> objects,
                   const std::vector<ObjectMotion>* reference, ByteWriter& out) {
    out.u8(uint8_t(objects.size()));
    for (const ObjectMotion& o : objects) {
        out.varint(o.id);
        const int box[4] = {o.x0, o.y0, o.x1 - o.x0, o.y1 - o.y0};
        if (const ObjectMotion* p = same_id(reference, o.id)) {
            const int before[4] = {p->x0, p->y0, p->x1 - p->x0, p->y1 - p->y0};
            for (int k = 0; k < 4; ++k) out.varint(zigzag(int64_t(box[k]) - before[k]));
            const auto a = floats(o);
            const auto b = floats(*p);
            for (std::size_t k = 0; k < a.size(); ++k)
                out.varint(std::bit_cast<uint32_t>(*a[k]) ^ std::bit_cast<uint32_t>(*b[k]));
        } else {
            for (int v : box) out.varint(uint64_t(v));
            for (const float* v : floats(o)) out.f32(*v);
        }
    }
}

Status read_objects(ByteReader& in, int width, int height,
                    const std::vector<ObjectMotion>* reference,
                    std::vector<ObjectMotion>& objects) {
    const int count = in.u8();
    if (count < 1 || count > kMaxObjects)
        return Status::error("camera section: " + std::to_string(count) + " objects (1.." +
                             std::to_string(kMaxObjects) + ")");
    objects.resize(std::size_t(count));
    double area = 0.0;
    for (int k = 0; k < count && in.ok(); ++k) {
        ObjectMotion& o = objects[std::size_t(k)];
        const std::string what = "camera section: object " + std::to_string(k);
        const uint64_t id = in.varint();
        if (!in.ok()) break;
        if (id == 0 || id > 0xFFFFFFFFu) return Status::error(what + ": id " + std::to_string(id));
        o.id = uint32_t(id);
        int64_t box[4];
        if (const ObjectMotion* p = same_id(reference, id)) {
            const int64_t before[4] = {p->x0, p->y0, p->x1 - p->x0, p->y1 - p->y0};
            for (int i = 0; i < 4; ++i) {
                const uint64_t u = in.varint();
                box[i] = u >> 40 ? -1 : before[i] + unzigzag(u);  // a change beyond any side
            }
            const auto a = floats(o);
            const auto b = floats(*p);
            for (std::size_t i = 0; i < a.size(); ++i) {
                const uint64_t v = in.varint();
                if (v > 0xFFFFFFFFu) in.fail("a float's xor is wider than 32 bits");
                *a[i] = std::bit_cast<float>(uint32_t(v) ^ std::bit_cast<uint32_t>(*b[i]));
            }
        } else {
            for (int64_t& v : box) {
                const uint64_t u = in.varint();
                v = u >> 40 ? -1 : int64_t(u);
            }
            for (float* v : floats(o)) *v = in.f32();
        }
        if (!in.ok()) break;
        if (box[0] < 0 || box[1] < 0 || box[2] < 1 || box[3] < 1 || box[0] + box[2] > width ||
            box[1] + box[3] > height)
            return Status::error(what + ": pixels outside the picture");
        o.x0 = int(box[0]), o.y0 = int(box[1]), o.x1 = int(box[0] + box[2]),
        o.y1 = int(box[1] + box[3]);
        area += double(box[2]) * double(box[3]);
        if (area > kMaxArea * width * height)
            return Status::error(what + ": objects cover more than 4 pictures");
        double norm = 0.0;
        for (float v : o.rotation) norm += double(v) * v;
        if (!(norm <= 1.0 + kQuaternionSlack)) return Status::error(what + ": not a rotation");
        for (float v : o.translation)
            if (!(std::abs(v) < kMaxTranslation)) return Status::error(what + ": translation");
    }
    if (!in.ok()) return Status::error(in.error());
    return {};
}

}  // namespace reprise::codec
