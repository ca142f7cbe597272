#pragma once
// Non-finite values at the door (docs/conventions.md, "Non-finite values"): every path counts
// them per channel and repairs them before any algorithm sees them, so nothing non-finite comes
// out. Colour (any component NaN/Inf): an invalid sample, a hole filled from its neighbours.
// Depth: +inf is background; NaN and -inf are unknown, filled from the farthest neighbours.
// Motion and normals (any component NaN/Inf): unknown, the mean of their neighbours.
// The fill is a pull-push over the valid pixels; a channel with no valid pixel becomes colour 0,
// depth +inf, motion 0, normal 0.
#include <cstddef>
#include <string>
#include <vector>

#include "reprise/core/frame.hpp"

namespace reprise {

struct NonfiniteCounts {
    std::size_t color = 0;   // pixels whose colour has a NaN/Inf component
    std::size_t depth = 0;   // depth NaN or -inf (+inf is background)
    std::size_t motion = 0;  // pixels whose motion has a NaN/Inf component
    std::size_t normal = 0;
    std::size_t ui = 0;      // UI-layer pixels (made transparent)
    std::size_t frames = 0;  // frames that held any of them

    std::size_t total() const { return color + depth + motion + normal + ui; }
    NonfiniteCounts& operator+=(const NonfiniteCounts& o) {
        color += o.color, depth += o.depth, motion += o.motion, normal += o.normal, ui += o.ui;
        frames += o.frames;
        return *this;
    }
};

// Counts only (rows in parallel; nothing written).
NonfiniteCounts count_nonfinite(const GBufferView& frame);

// Repairs non-finite values in place; sizes its scratch on first use. A channel without
// non-finite values is read once and left untouched (bit for bit).
class NonfiniteRepair {
public:
    std::size_t repair_color(ImageView<glm::vec4> color);
    std::size_t repair_depth(ImageView<float> depth);
    std::size_t repair_motion(ImageView<glm::vec2> motion);
    std::size_t repair_normal(ImageView<glm::vec3> normal);
    std::size_t repair_ui(ImageView<glm::vec4> ui);  // premultiplied RGBA: NaN/Inf -> 0
    NonfiniteCounts repair(Frame& frame);            // every channel, the UI layer too

    // `frame` itself when it holds no non-finite value; otherwise a copy of it (kept here until
    // the next call) with them repaired. Copies only the frames that need it.
    const Frame& clean(const Frame& frame, NonfiniteCounts& counts);
    // The same for a view (colour, depth, motion, normal, id; the camera comes along).
    GBufferView clean(const GBufferView& frame, NonfiniteCounts& counts);
    // A lone colour image (the upsampler's low-resolution colour).
    ImageView<const glm::vec4> clean(ImageView<const glm::vec4> color, std::size_t& count);

private:
    std::vector<glm::vec4> pyramid_;  // pull-push levels, 4 floats a pixel whatever the channel
    std::vector<float> weights_;
    Frame copy_;
    Image<glm::vec4> color_copy_;
};

// What a command prints once per sequence when counts.total() > 0, e.g. "1234 non-finite values
// (colour 400, depth 420, motion 414) in 4 frames: colour treated as holes, depth and motion as
// unknown, filled from their neighbours".
std::string describe_nonfinite(const NonfiniteCounts& counts);

}  // namespace reprise
