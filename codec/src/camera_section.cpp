// The camera of a frame: flags for what equals the reference's camera; on inter frames the rest
// as each float's bits xor the reference's (a moving camera changes low mantissa bits), raw on
// key frames.
#include <bit>

#include "internal.hpp"
#include "reprise/core/byte_io.hpp"

namespace reprise::codec {

namespace {

enum : uint8_t {
    kSameView = 1,
    kPrevIsReference = 2,
    kSameLens = 4,
    kSameProjection = 8,
    kObjects = 16
};
constexpr uint8_t kAllFlags = kSameView | kPrevIsReference | kSameLens | kSameProjection | kObjects;

// `base`: the reference's matrix (xor-varint coding) or null (raw f32).
void write_mat(ByteWriter& w, const glm::mat4& m, const glm::mat4* base) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            if (base)
                w.varint(std::bit_cast<uint32_t>(m[c][r]) ^ std::bit_cast<uint32_t>((*base)[c][r]));
            else
                w.f32(m[c][r]);
        }
}
glm::mat4 read_mat(ByteReader& r, const glm::mat4* base) {
    glm::mat4 m;
    for (int c = 0; c < 4; ++c)
        for (int k = 0; k < 4; ++k) {
            if (!base) {
                m[c][k] = r.f32();
                continue;
            }
            const uint64_t v = r.varint();
            if (v > 0xFFFFFFFFu) r.fail("a matrix element's xor is wider than 32 bits");
            m[c][k] = std::bit_cast<float>(uint32_t(v) ^ std::bit_cast<uint32_t>((*base)[c][k]));
        }
    return m;
}
bool same_lens(const Camera& a, const Camera& b) {
    return a.near == b.near && a.far == b.far && a.jitter == b.jitter;
}

}  // namespace

std::size_t encode_camera(const Camera& c, double time, const Picture* ref,
                          std::span<const ObjectMotion> objects, std::vector<uint8_t>& out) {
    ByteWriter w(out);
    uint8_t flags = 0;
    const glm::mat4 *view = nullptr, *projection = nullptr;
    if (ref) {
        const Camera& rc = ref->camera;
        view = &rc.view, projection = &rc.projection;
        if (c.view == rc.view) flags |= kSameView;
        if (c.projection == rc.projection) flags |= kSameProjection;
        if (c.prev_view == rc.view && c.prev_projection == rc.projection) flags |= kPrevIsReference;
        if (same_lens(c, rc)) flags |= kSameLens;
    }
    if (!objects.empty()) flags |= kObjects;
    w.u8(flags);
    if (!(flags & kSameView)) write_mat(w, c.view, view);
    if (!(flags & kSameProjection)) write_mat(w, c.projection, projection);
    if (!(flags & kPrevIsReference)) {
        write_mat(w, c.prev_view, view);
        write_mat(w, c.prev_projection, projection);
    }
    if (!(flags & kSameLens)) {
        w.f32(c.near);
        w.f32(c.far);
        w.f32(c.jitter.x);
        w.f32(c.jitter.y);
    }
    w.f64(time);
    const std::size_t before = out.size();
    if (!objects.empty()) write_objects(objects, ref ? &ref->objects : nullptr, w);
    return out.size() - before;
}

Status decode_camera(std::span<const uint8_t> in, const Picture* ref, Camera& c, double& time,
                     int width, int height, std::vector<ObjectMotion>& objects,
                     std::size_t& object_bytes) {
    ByteReader r(in, "camera section");
    const uint8_t flags = r.u8();
    if (flags & ~kAllFlags)
        return Status::error("camera section: unknown flags " + std::to_string(flags));
    if ((flags & ~kObjects) && !ref)
        return Status::error("camera section: refers to the reference camera of a key frame");
    const glm::mat4* view = ref ? &ref->camera.view : nullptr;
    const glm::mat4* projection = ref ? &ref->camera.projection : nullptr;
    c.view = flags & kSameView ? ref->camera.view : read_mat(r, view);
    c.projection = flags & kSameProjection ? ref->camera.projection : read_mat(r, projection);
    if (flags & kPrevIsReference) {
        c.prev_view = ref->camera.view;
        c.prev_projection = ref->camera.projection;
    } else {
        c.prev_view = read_mat(r, view);
        c.prev_projection = read_mat(r, projection);
    }
    if (flags & kSameLens) {
        c.near = ref->camera.near;
        c.far = ref->camera.far;
        c.jitter = ref->camera.jitter;
    } else {
        c.near = r.f32();
        c.far = r.f32();
        c.jitter = {r.f32(), r.f32()};
    }
    time = r.f64();
    c.time = time;
    if (!r.ok()) return Status::error(r.error());
    objects.clear();
    const std::size_t before = r.position();
    if (flags & kObjects)
        REPRISE_TRY(read_objects(r, width, height, ref ? &ref->objects : nullptr, objects));
    object_bytes = r.position() - before;
    if (r.remaining())
        return Status::error("camera section: " + std::to_string(r.remaining()) +
                             " bytes left over");
    return {};
}

}  // namespace reprise::codec
