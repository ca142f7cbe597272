#include "reprise/warp/reproject.hpp"

namespace reprise::warp {

ConstPayload payload_of(ImageView<const glm::vec4> rgba) {
    return {reinterpret_cast<const float*>(rgba.data), rgba.width, rgba.height, 4, rgba.stride * 4};
}

Payload payload_of(ImageView<glm::vec4> rgba) {
    return {reinterpret_cast<float*>(rgba.data), rgba.width, rgba.height, 4, rgba.stride * 4};
}

}  // namespace reprise::warp
