#pragma once
// One rendered instant: the G-buffer and the camera. Conventions in docs/conventions.md.
#include <cstdint>

#include <glm/mat4x4.hpp>

#include "reprise/core/image.hpp"

namespace reprise {

// OpenGL conventions: the camera looks down -Z; clip space has w = -z_view.
struct Camera {
    glm::mat4 view{1.0f};             // world -> camera
    glm::mat4 projection{1.0f};       // camera -> clip, without jitter
    glm::mat4 prev_view{1.0f};        // the previous frame's pair
    glm::mat4 prev_projection{1.0f};
    float near = 0.1f;                // scene units
    float far = 1000.0f;
    glm::vec2 jitter{0.0f};           // sub-pixel offset of the rendered samples, pixels
    double time = 0.0;                // seconds on the animation timeline
};

struct Frame {
    Image<glm::vec4> color;    // linear-light RGB, A = coverage (1 geometry, 0 background)
    Image<float> depth;        // linear view depth, scene units; background +inf
    Image<glm::vec2> motion;   // backward motion, pixels: p + motion = p in the previous frame
    Image<glm::vec3> normal;   // world-space unit normal (0 on background)
    Image<uint32_t> id;        // object id, 0 = background
    Camera camera;
    double fps = 0.0;          // frame rate of the sequence this frame belongs to (0 = unknown)

    int width() const { return color.width(); }
    int height() const { return color.height(); }
};

// The display value of linear light: clamp to [0, 1], then the sRGB transfer function.
float linear_to_srgb(float linear);
float srgb_to_linear(float encoded);

}  // namespace reprise
