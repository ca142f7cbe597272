#pragma once
// Motion of whole objects (object_motion.cpp): per object id the encoder fits a rigid transform
// to the renderer's motion and sends it with the pixels it may cover; both sides derive each
// pixel's motion from it, decoded depth and the cameras (docs/bitstream.md, section 7).
#include <cstdint>
#include <span>
#include <vector>

#include <glm/mat4x4.hpp>

#include "reprise/core/byte_io.hpp"
#include "reprise/core/camera.hpp"
#include "reprise/core/image.hpp"
#include "reprise/core/status.hpp"

namespace reprise::codec {

inline constexpr int kMaxObjects = 32;  // per frame

struct ObjectMotion {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // the pixels it may cover (x1, y1 excluded)
    // Where a point of the object was one frame earlier, in this frame's camera space:
    // X -> R X + t, R the unit quaternion (rotation, sqrt(1 - |rotation|^2)).
    float rotation[3] = {0, 0, 0};
    float translation[3] = {0, 0, 0};
    uint32_t id = 0;  // the renderer's object id it was fitted to (not 0)

    glm::dmat4 matrix() const;
};

// One object's motion at the pixels it may cover (NaN elsewhere), and the depth each pixel's
// point had in the previous frame's camera. Id 0: the cameras' motion (no depth).
struct ObjectField {
    uint32_t id = 0;
    int x0 = 0, y0 = 0;
    Image<glm::vec2> motion;
    Image<float> depth;
    glm::vec2 at(int x, int y) const;
};

// Objects (ids other than 0) with at least 16 pixels whose `motion` the camera motion `base`
// does not explain within `bound`, the 32 with most such pixels, each kept when its fitted
// transform explains more of its pixels than the cameras do; an object's `previous` transform
// (same id) when it explains as much. Deterministic.
std::vector<ObjectMotion> fit_object_motions(const Camera& camera, ImageView<const float> depth,
                                             ImageView<const uint32_t> ids,
                                             ImageView<const glm::vec2> motion,
                                             ImageView<const glm::vec2> base, float bound,
                                             std::span<const ObjectMotion> previous);

// Each object's motion field from decoded depth (both sides, bit for bit).
void object_fields(const Camera& camera, ImageView<const float> depth,
                   std::span<const ObjectMotion> objects, std::vector<ObjectField>& fields);

// The object each pixel is predicted to move with (both sides, bit for bit; 0: none): the first
// of `fields` in `objects` (bit k: fields[k]) whose motion takes the pixel to a reference pixel
// that moved with the same object, at the depth the reference has there within 1/16. True when
// any pixel has one.
bool predict_owners(std::span<const ObjectField> fields, uint32_t objects,
                    ImageView<const float> reference_depth,
                    ImageView<const uint32_t> reference_owner, ImageView<uint32_t> out);

// Each object raw, or, when `reference` (the reference picture's objects) has its id, as the
// xor of its floats' bits with that one's and the change of its pixels.
void write_objects(std::span<const ObjectMotion> objects,
                   const std::vector<ObjectMotion>* reference, ByteWriter& out);
Status read_objects(ByteReader& in, int width, int height,
                    const std::vector<ObjectMotion>* reference, std::vector<ObjectMotion>& objects);

}  // namespace reprise::codec
