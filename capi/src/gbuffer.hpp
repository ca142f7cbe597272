#pragma once
// reprise_gbuffer <-> Frame: every channel checked (pointer, size, stride, format) and converted
// from / to the caller's pixel format; the camera between C arrays and glm.
#include <cstdint>

#include <glm/ext/vector_uint4_sized.hpp>

#include "reprise.h"
#include "reprise/core/frame.hpp"

namespace reprise::capi {

// Channels of a G-buffer, as a mask of what a call reads or writes.
enum Channel : unsigned {
    kColor = 1u << 0,
    kDepth = 1u << 1,
    kMotion = 1u << 2,
    kNormal = 1u << 3,
    kId = 1u << 4,
    kUi = 1u << 5,
};

// Copies the channels in `read` that `given` has (colour always, required) into `frame`,
// converted to its float layout; the others are cleared. `name` is the argument's name in
// messages ("frame"). Reuses frame's buffers while the size stays the same. `reset` becomes
// frame.camera.cut. With `display`, colour may come as RGBA8_SRGB: its bytes go there and
// frame.color is cleared (else `display` is).
reprise_status read_gbuffer(const char* function, const char* name, const reprise_gbuffer* given,
                            unsigned read, Frame& frame, Image<glm::u8vec4>* display = nullptr);

// Checks `out` for a width x height result: colour required (RGBA8_SRGB when `srgb8`, else a
// float format), the channels in `written` optional, any other channel must be absent.
reprise_status check_output(const char* function, const reprise_gbuffer* out, int width, int height,
                            unsigned written, bool srgb8 = false);
// Writes the channels `out` asks for (checked by check_output) and the camera and fps; the
// colour from `display` when it holds any. Channels `frame` lacks are an error, before anything
// is written.
reprise_status write_gbuffer(const char* function, const Frame& frame, reprise_gbuffer* out,
                             const Image<glm::u8vec4>* display = nullptr);

}  // namespace reprise::capi

namespace reprise::capi {

// A made frame pulled from a C++ object so that the caller can be told its size, kept until it
// is received (converter, decoder).
struct HeldFrame {
    Frame frame;
    Image<glm::u8vec4> display;  // the colour as RGBA8_SRGB instead (a display decoder)
    bool held = false;
    int width() const { return display.empty() ? frame.width() : display.width(); }
    int height() const { return display.empty() ? frame.height() : display.height(); }
};
// REPRISE_OK with the held frame's size, or REPRISE_NEED_MORE when none is held.
reprise_status held_size(const char* function, const HeldFrame& next, int32_t* width,
                         int32_t* height);
// Writes the held frame into `out` (check_output with `written`) and lets it go; NEED_MORE when
// none is held; on an error it stays held.
reprise_status receive_held(const char* function, HeldFrame& next, unsigned written,
                            reprise_gbuffer* out);

}  // namespace reprise::capi
