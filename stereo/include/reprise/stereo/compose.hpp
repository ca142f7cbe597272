#pragma once
// A stereo pair as one picture for people to look at: side by side, top-bottom or anaglyph.
#include "reprise/core/visualize.hpp"

namespace reprise::stereo {

enum class Layout {
    SideBySide,  // left | right, full width each (2W x H)
    TopBottom,   // left over right (W x 2H)
    Anaglyph,    // red-cyan, Dubois least-squares (W x H)
};

// Both eyes linear RGBA of the same size (a mismatch is a broken contract). `out` is resized.
void compose(ImageView<const glm::vec4> left, ImageView<const glm::vec4> right, Layout layout,
             Image<Rgb8>& out);

}  // namespace reprise::stereo
