// The camera of a frame: flags for what equals the reference's camera; on inter frames the rest
// as each float's bits xor the reference's (a moving camera changes low mantissa bits); on key
// frames each float as 0, 1, -1 or raw, and the previous view and projection xor this frame's.
#include <algorithm>
#include <bit>
#include <cstring>

#include "internal.hpp"
#include "reprise/core/byte_io.hpp"

namespace reprise::codec {

namespace {

enum : uint8_t {
    kSameView = 1,
    kPrevIsReference = 2,
    kSameLens = 4,
    kSameProjection = 8,
    kObjects = 16,
    kPrevIsThis = 32
};
constexpr uint8_t kAllFlags =
    kSameView | kPrevIsReference | kSameLens | kSameProjection | kObjects | kPrevIsThis;

// Key frames: a 2-bit code per float, four to a byte (0: +0, 1: 1, 2: -1, 3: the f32 follows),
// then the f32s of code 3: a projection's zeros and a view's last row cost a quarter byte each.
constexpr uint32_t kCodedBits[3] = {0x00000000u, 0x3F800000u, 0xBF800000u};

int float_code(float v) {
    int code = 0;
    while (code < 3 && kCodedBits[code] != std::bit_cast<uint32_t>(v)) ++code;
    return code;
}
void write_floats(ByteWriter& w, const float* v, int n) {
    uint8_t packed = 0;
    for (int i = 0; i < n; ++i) {
        packed |= uint8_t(float_code(v[i]) << (2 * (i % 4)));
        if (i % 4 == 3 || i == n - 1) w.u8(packed), packed = 0;
    }
    for (int i = 0; i < n; ++i)
        if (float_code(v[i]) == 3) w.f32(v[i]);
}
void read_floats(ByteReader& r, float* v, int n) {
    uint8_t codes[16];
    for (int i = 0; i < n; i += 4) {
        const uint8_t packed = r.u8();
        for (int k = i; k < std::min(n, i + 4); ++k) codes[k] = (packed >> (2 * (k - i))) & 3;
    }
    for (int i = 0; i < n; ++i)
        v[i] = codes[i] == 3 ? r.f32() : std::bit_cast<float>(kCodedBits[codes[i]]);
}

// `base`: a matrix the bits are xor-ed with (varint coding), or null (write_floats).
void write_mat(ByteWriter& w, const glm::mat4& m, const glm::mat4* base) {
    if (!base) return write_floats(w, &m[0][0], 16);
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            w.varint(std::bit_cast<uint32_t>(m[c][r]) ^ std::bit_cast<uint32_t>((*base)[c][r]));
}
glm::mat4 read_mat(ByteReader& r, const glm::mat4* base) {
    glm::mat4 m;
    if (!base) {
        read_floats(r, &m[0][0], 16);
        return m;
    }
    for (int c = 0; c < 4; ++c)
        for (int k = 0; k < 4; ++k) {
            const uint64_t v = r.varint();
            if (v > 0xFFFFFFFFu) r.fail("a matrix element's xor is wider than 32 bits");
            m[c][k] = std::bit_cast<float>(uint32_t(v) ^ std::bit_cast<uint32_t>((*base)[c][k]));
        }
    return m;
}
bool bits_equal(const glm::mat4& a, const glm::mat4& b) {
    return std::memcmp(&a[0][0], &b[0][0], sizeof(glm::mat4)) == 0;
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
    if (!(flags & kPrevIsReference) && bits_equal(c.prev_view, c.view) &&
        bits_equal(c.prev_projection, c.projection))
        flags |= kPrevIsThis;
    if (!objects.empty()) flags |= kObjects;
    w.u8(flags);
    if (!(flags & kSameView)) write_mat(w, c.view, view);
    if (!(flags & kSameProjection)) write_mat(w, c.projection, projection);
    if (!(flags & (kPrevIsReference | kPrevIsThis))) {  // a key frame's: xor this frame's
        write_mat(w, c.prev_view, view ? view : &c.view);
        write_mat(w, c.prev_projection, projection ? projection : &c.projection);
    }
    if (!(flags & kSameLens)) {
        const float lens[4] = {c.near, c.far, c.jitter.x, c.jitter.y};
        write_floats(w, lens, 4);
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
    if ((flags & ~(kObjects | kPrevIsThis)) && !ref)
        return Status::error("camera section: refers to the reference camera of a key frame");
    if ((flags & kPrevIsReference) && (flags & kPrevIsThis))
        return Status::error("camera section: flags 2 and 32 both give the previous camera");
    const glm::mat4* view = ref ? &ref->camera.view : nullptr;
    const glm::mat4* projection = ref ? &ref->camera.projection : nullptr;
    c.view = flags & kSameView ? ref->camera.view : read_mat(r, view);
    c.projection = flags & kSameProjection ? ref->camera.projection : read_mat(r, projection);
    if (flags & kPrevIsReference) {
        c.prev_view = ref->camera.view;
        c.prev_projection = ref->camera.projection;
    } else if (flags & kPrevIsThis) {
        c.prev_view = c.view;
        c.prev_projection = c.projection;
    } else {
        c.prev_view = read_mat(r, view ? view : &c.view);
        c.prev_projection = read_mat(r, projection ? projection : &c.projection);
    }
    if (flags & kSameLens) {
        c.near = ref->camera.near;
        c.far = ref->camera.far;
        c.jitter = ref->camera.jitter;
    } else {
        float lens[4];
        read_floats(r, lens, 4);
        c.near = lens[0], c.far = lens[1], c.jitter = {lens[2], lens[3]};
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
