#include <algorithm>
#include <cmath>

#include "reprise/core/frame.hpp"

namespace reprise {

float linear_to_srgb(float linear) {
    // NaN maps to 0, like any other invalid light.
    float c = std::isnan(linear) ? 0.0f : std::clamp(linear, 0.0f, 1.0f);
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

float srgb_to_linear(float encoded) {
    float c = std::isnan(encoded) ? 0.0f : std::clamp(encoded, 0.0f, 1.0f);
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

}  // namespace reprise
