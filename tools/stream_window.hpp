#pragma once
// `reprise connect --window / --interactive`: the displayed frames in an SDL2 window, and a
// free camera moved by keys (WASD, Q/E down/up, arrows turn) and mouse drags.
#include <memory>

#include "reprise/core/frame.hpp"
#include "reprise/core/status.hpp"

namespace reprise::cli {

class StreamWindow {
public:
    // Fails (a Status, no crash) where SDL2 finds no display. `software`: SDL's software
    // renderer (no GL context of its own, for a thread that makes another GL context current).
    static Status open(bool interactive, const glm::mat4& start_view, bool software,
                       std::unique_ptr<StreamWindow>& window);
    ~StreamWindow();

    // Handles pending events and moves the camera by `dt` seconds; false once the window closed.
    bool pump(double dt);
    glm::mat4 view() const;  // world -> camera of the interactive camera
    void show(const GBufferView& frame);

    struct State;

private:
    StreamWindow();
    std::unique_ptr<State> state_;
};

}  // namespace reprise::cli
