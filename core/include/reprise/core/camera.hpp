#pragma once
// The camera of one rendered instant. Conventions in docs/conventions.md.
#include <cstdint>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>

namespace reprise {

// Whether a shot cut (or any jump of the camera) lies between the previous frame and this one:
// then nothing before this frame predicts it (prev_view, prev_projection and the motion say
// nothing). The renderer knows; only frames that do not say (Unknown) are tested on their pixels.
enum class Cut : uint8_t { Unknown = 0, No = 1, Yes = 2 };

// OpenGL conventions: the camera looks down -Z; clip space has w = -z_view.
struct Camera {
    glm::mat4 view{1.0f};        // world -> camera
    glm::mat4 projection{1.0f};  // camera -> clip, without jitter
    glm::mat4 prev_view{1.0f};   // the previous frame's pair
    glm::mat4 prev_projection{1.0f};
    float near = 0.1f;  // scene units
    float far = 1000.0f;
    glm::vec2 jitter{0.0f};  // sub-pixel offset of the rendered samples, pixels
    double time = 0.0;       // seconds on the animation timeline
    Cut cut = Cut::Unknown;
};

// False for a default Camera (identity projection): the input carried no camera (Blender's
// render passes, plain video).
inline bool has_projection(const Camera& camera) { return camera.projection != glm::mat4(1.0f); }

}  // namespace reprise
