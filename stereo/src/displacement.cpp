// Per-pixel displacement from one camera to another through depth: warp's, which has the
// dispatched row kernel.
#include "reprise/warp/displacement.hpp"
#include "reprise/stereo/synthesize.hpp"

namespace reprise::stereo {

void stereo_displacement(const GBufferView& source, const Camera& target,
                         ImageView<glm::vec2> displacement, ImageView<float> target_depth) {
    warp::camera_displacement(source, target, displacement, target_depth);
}

}  // namespace reprise::stereo
