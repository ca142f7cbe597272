#pragma once
// Camera motion fitted from depth and backward motion, for frames that carry no camera: the
// rigid motion (and optionally the focal length) that best explains the motion of most pixels.
#include <glm/mat4x4.hpp>

#include "reprise/core/image.hpp"

namespace reprise::codec {

struct CameraFit {
    bool ok = false;             // false: too few usable pixels or no convergence (relative = I)
    glm::dmat4 relative{1.0};    // this frame's camera space -> the previous frame's camera space
    glm::mat4 projection{1.0f};  // the projection the fit used (its focal fitted on request)
    int samples = 0, inliers = 0;
    double rms_px = 0.0;  // reprojection error of the inliers
};

// A symmetric perspective projection with a 50 degree vertical field of view (near 0.1, far
// 1000), the lens the fit assumes when a frame has none.
glm::mat4 assumed_projection(int width, int height);

// Fits on a grid of about 2000 pixels with finite positive depth (+inf: background, a direction
// that only rotation moves) and finite motion, by Levenberg-Marquardt on the reprojection error,
// rounds of trimming rejecting what moves on its own. `projection` must be a symmetric
// perspective one; with fit_focal its focal length is a seventh parameter (same scale on both
// axes). Deterministic; never NaN.
CameraFit fit_camera(ImageView<const float> depth, ImageView<const glm::vec2> motion,
                     const glm::mat4& projection, bool fit_focal);

}  // namespace reprise::codec
