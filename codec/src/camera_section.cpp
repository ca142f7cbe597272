// The camera of a frame: flags for what equals the reference's camera, the rest raw.
#include "internal.hpp"
#include "reprise/core/byte_io.hpp"

namespace reprise::codec {

namespace {

enum : uint8_t { kSamePose = 1, kPrevIsReference = 2, kSameLens = 4 };

void write_mat(ByteWriter& w, const glm::mat4& m) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) w.f32(m[c][r]);
}
glm::mat4 read_mat(ByteReader& r) {
    glm::mat4 m;
    for (int c = 0; c < 4; ++c)
        for (int k = 0; k < 4; ++k) m[c][k] = r.f32();
    return m;
}
bool same_lens(const Camera& a, const Camera& b) {
    return a.near == b.near && a.far == b.far && a.jitter == b.jitter;
}

}  // namespace

void encode_camera(const Camera& c, double time, const Picture* ref, std::vector<uint8_t>& out) {
    ByteWriter w(out);
    uint8_t flags = 0;
    if (ref) {
        const Camera& rc = ref->camera;
        if (c.view == rc.view && c.projection == rc.projection) flags |= kSamePose;
        if (c.prev_view == rc.view && c.prev_projection == rc.projection) flags |= kPrevIsReference;
        if (same_lens(c, rc)) flags |= kSameLens;
    }
    w.u8(flags);
    if (!(flags & kSamePose)) {
        write_mat(w, c.view);
        write_mat(w, c.projection);
    }
    if (!(flags & kPrevIsReference)) {
        write_mat(w, c.prev_view);
        write_mat(w, c.prev_projection);
    }
    if (!(flags & kSameLens)) {
        w.f32(c.near);
        w.f32(c.far);
        w.f32(c.jitter.x);
        w.f32(c.jitter.y);
    }
    w.f64(time);
}

Status decode_camera(std::span<const uint8_t> in, const Picture* ref, Camera& c, double& time) {
    ByteReader r(in, "camera section");
    const uint8_t flags = r.u8();
    if (flags & ~uint8_t(kSamePose | kPrevIsReference | kSameLens))
        return Status::error("camera section: unknown flags " + std::to_string(flags));
    if ((flags & (kSamePose | kPrevIsReference | kSameLens)) && !ref)
        return Status::error("camera section: refers to the reference camera of a key frame");
    if (flags & kSamePose) {
        c.view = ref->camera.view;
        c.projection = ref->camera.projection;
    } else {
        c.view = read_mat(r);
        c.projection = read_mat(r);
    }
    if (flags & kPrevIsReference) {
        c.prev_view = ref->camera.view;
        c.prev_projection = ref->camera.projection;
    } else {
        c.prev_view = read_mat(r);
        c.prev_projection = read_mat(r);
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
    if (r.remaining())
        return Status::error("camera section: " + std::to_string(r.remaining()) +
                             " bytes left over");
    return {};
}

}  // namespace reprise::codec
