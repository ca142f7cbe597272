#pragma once
// One rendered instant: the G-buffer and the camera. Conventions in docs/conventions.md.
#include <cstdint>

#include "reprise/core/gbuffer.hpp"

namespace reprise {

struct Frame {
    Image<glm::vec4> color;   // linear-light RGB, A = coverage (1 geometry, 0 background)
    Image<float> depth;       // linear view depth, scene units; background +inf
    Image<glm::vec2> motion;  // backward motion, pixels: p + motion = p in the previous frame
    Image<glm::vec3> normal;  // world-space unit normal (0 on background)
    Image<uint32_t> id;       // object id, 0 = background
    // UI/HUD layer, premultiplied RGBA (EXR ui.R ui.G ui.B ui.A): drawn over the colour for
    // display, never warped; the colour holds the scene without it.
    Image<glm::vec4> ui;
    Camera camera;
    double fps = 0.0;  // frame rate of the sequence this frame belongs to (0 = unknown)

    int width() const { return color.width(); }
    int height() const { return color.height(); }

    GBufferView view() const {
        return {color.view(), depth.view(), motion.view(), normal.view(), id.view(), camera, fps};
    }
    operator GBufferView() const { return view(); }  // NOLINT: a Frame is a G-buffer
    // A copy of the view's channels and camera (no UI layer); buffers of the same size are reused.
    void assign(const GBufferView& v) {
        color.assign(v.color), depth.assign(v.depth), motion.assign(v.motion);
        normal.assign(v.normal), id.assign(v.id), ui.clear();
        camera = v.camera, fps = v.fps;
    }
};

// The display value of linear light: clamp to [0, 1], then the sRGB transfer function.
float linear_to_srgb(float linear);
float srgb_to_linear(float encoded);

// colour with the UI layer over it (premultiplied "over"): rgb = ui.rgb + (1 - ui.a) rgb,
// a = ui.a + (1 - ui.a) a. `out` may be `color` itself; without a UI it is a copy.
void composite_ui(ImageView<const glm::vec4> color, ImageView<const glm::vec4> ui,
                  ImageView<glm::vec4> out);

}  // namespace reprise
