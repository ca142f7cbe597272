#pragma once
// `reprise connect --window / --interactive`: the displayed frames in an SDL2 window, and a
// free camera moved by keys (WASD, Q/E down/up, arrows turn) and mouse drags.
#include <memory>

#include "reprise/core/frame.hpp"
#include "reprise/core/status.hpp"
#include "reprise/gpu/context.hpp"

namespace reprise::cli {

class StreamWindow {
public:
    enum class Drawing {
        Sdl,          // SDL's renderer, frames uploaded as 8-bit RGB
        SdlSoftware,  // the same, software (no GL context of its own)
        GlEs,  // an OpenGL ES 3.1 context of the window's, current on the opening thread from open
               // on, in which the GPU backend works (gpu::Context::adopt_current): the frames it
               // made are drawn from their textures, with no round trip through the CPU
    };
    // Fails (a Status, no crash) where SDL2 finds no display, or (GlEs) no OpenGL ES 3.1.
    static Status open(bool interactive, const glm::mat4& start_view, Drawing drawing,
                       std::unique_ptr<StreamWindow>& window);
    ~StreamWindow();

    // Handles pending events and moves the camera by `dt` seconds; false once the window closed.
    bool pump(double dt);
    glm::mat4 view() const;  // world -> camera of the interactive camera
    // Colour as display values (sRGB of linear colour clamped to [0, 1], NaN 0) scaled to the
    // window, nearest pixel; then presented. An error names what SDL or GL refused.
    Status show(const GBufferView& frame);
    // Whether the window draws in its own OpenGL ES context (Drawing::GlEs).
    bool draws_textures() const;
    // GlEs: a frame on the GPU (its colour texture), the same way; an error without one.
    Status show(const gpu::MadeTextures& frame);

    struct State;

private:
    StreamWindow();
    std::unique_ptr<State> state_;
};

}  // namespace reprise::cli
