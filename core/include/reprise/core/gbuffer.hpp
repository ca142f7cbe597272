#pragma once
// The non-owning G-buffer descriptor every warp and stereo entry point takes: views of the
// rendered channels and the camera, nothing copied. A Frame converts to it for free
// (frame.view(), or implicitly). Any channel a stage does not need may be empty.
#include <cstdint>

#include "reprise/core/camera.hpp"
#include "reprise/core/image.hpp"

namespace reprise {

struct GBufferView {
    ImageView<const glm::vec4> color;  // linear-light RGB, A = coverage (1 geometry, 0 background)
    ImageView<const float> depth;      // linear view depth (positive, scene units); background +inf
    ImageView<const glm::vec2>
        motion;  // backward motion in pixels: p + motion = p in the previous frame
    ImageView<const glm::vec3> normal;  // world-space unit normal (0 on background)
    ImageView<const uint32_t> id;       // object id, 0 = background
    Camera camera;                      // view/projection of this instant and the previous one
    double fps = 0.0;  // frame rate of the sequence this frame belongs to (0 = unknown)

    // The size of the colour, as Frame has it.
    int width() const { return color.width; }
    int height() const { return color.height; }

    // Motion present and zero at every pixel: nothing moved (a still frame is copied, not warped).
    bool motion_is_zero() const {
        if (motion.empty()) return false;
        for (int y = 0; y < motion.height; ++y) {
            const glm::vec2* m = motion.row(y);
            for (int x = 0; x < motion.width; ++x)
                if (m[x].x != 0.0f || m[x].y != 0.0f) return false;
        }
        return true;
    }
};

}  // namespace reprise
