#pragma once
// Colour on a scale close to the display's, for warping, blending and filling
// (FrucOptions::perceptual, stereo::StereoOptions::perceptual): r, g and b as the square root of
// their magnitude, sign kept; alpha as it is. Resampled edges and blends then come out nearer
// what the display shows of the rendered truth than those made in linear light.
#include "reprise/core/image.hpp"

#include <glm/vec4.hpp>

namespace reprise::warp {

// `color` encoded into `encoded` (sized here); returns its view.
ImageView<const glm::vec4> encode_perceptual(ImageView<const glm::vec4> color,
                                             Image<glm::vec4>& encoded);
// Encoded colour back to linear light, in place.
void decode_perceptual(ImageView<glm::vec4> color);

}  // namespace reprise::warp
