// Colour warped, blended and filled on a scale close to the display's (the square root of linear
// light), brought back to linear light in the made frame.
#include "reprise/warp/perceptual.hpp"

#include <cmath>

#include "fruc_stages.hpp"
#include "kernels.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::warp {

void perceptual_encode_row_reference(const glm::vec4* from, glm::vec4* to, int width) {
    for (int x = 0; x < width; ++x) {
        const glm::vec4 c = from[x];
        for (int k = 0; k < 3; ++k) to[x][k] = std::copysign(std::sqrt(std::abs(c[k])), c[k]);
        to[x].a = c.a;
    }
}

void perceptual_decode_row_reference(glm::vec4* color, int width) {
    for (int x = 0; x < width; ++x)
        for (int k = 0; k < 3; ++k) color[x][k] *= std::abs(color[x][k]);
}

ImageView<const glm::vec4> encode_perceptual(ImageView<const glm::vec4> color,
                                             Image<glm::vec4>& encoded) {
    encoded.resize(color.width, color.height);
    parallel_for(0, color.height, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            perceptual_encode_row(color.row(y), &encoded(0, y), color.width);
    });
    return std::as_const(encoded).view();
}

void decode_perceptual(ImageView<glm::vec4> color) {
    parallel_for(0, color.height, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) perceptual_decode_row(color.row(y), color.width);
    });
}

bool encodes_colour(const FrucOptions& options) {
    return options.perceptual && options.backend == nullptr;
}

void finish_colour(ImageView<glm::vec4> color, const FrucOptions& options) {
    if (encodes_colour(options)) decode_perceptual(color);
}

}  // namespace reprise::warp
