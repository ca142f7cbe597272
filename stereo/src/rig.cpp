// Stereo rigs: eye views, off-axis projections, disparity and the choice of rendered eye.
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

#include "reprise/stereo/rig.hpp"

namespace reprise::stereo {

namespace {

// The view of an eye at camera-space x = offset.
glm::mat4 offset_view(const glm::mat4& view, float offset) {
    return glm::translate(glm::mat4(1.0f), glm::vec3(-offset, 0.0f, 0.0f)) * view;
}

// Shifts the projection centre so that camera-space points at depth `convergence` on the rig's
// centre line keep their NDC: x_ndc = P00 * x / z - P[2][0].
glm::mat4 off_axis(glm::mat4 projection, float offset, float convergence) {
    projection[2][0] -= projection[0][0] * offset / convergence;
    return projection;
}

Camera eye(const Camera& centre, const StereoRig& rig, float offset) {
    Camera c = centre;
    c.view = offset_view(centre.view, offset);
    c.prev_view = offset_view(centre.prev_view, offset);
    if (rig.rig == Rig::OffAxis && std::isfinite(rig.convergence) && rig.convergence > 0.0f) {
        c.projection = off_axis(centre.projection, offset, rig.convergence);
        c.prev_projection = off_axis(centre.prev_projection, offset, rig.convergence);
    }
    return c;
}

}  // namespace

EyeCameras eye_cameras(const Camera& camera, const StereoRig& rig, Anchor anchor) {
    const float half = 0.5f * rig.ipd;
    if (anchor == Anchor::Centre) return {eye(camera, rig, -half), eye(camera, rig, half)};
    // The given eye stays exactly as it is; the other is one ipd away (right of the left eye).
    const float to_other = anchor == Anchor::Left ? rig.ipd : -rig.ipd;
    Camera other_eye = eye(camera, rig, to_other);
    if (anchor == Anchor::Left) return {camera, other_eye};
    return {other_eye, camera};
}

float disparity_px(const StereoRig& rig, const glm::mat4& projection, int width, float depth) {
    const float f = projection[0][0] * 0.5f * float(width);
    const float inv_c =
        rig.rig == Rig::OffAxis && rig.convergence > 0.0f ? 1.0f / rig.convergence : 0.0f;
    return f * rig.ipd * (1.0f / depth - inv_c);
}

Eye choose_rendered_eye(const Camera& camera, const StereoRig& rig, Eye previous, float dead_zone) {
    const glm::vec3 now = glm::vec3(glm::inverse(camera.view)[3]);
    const glm::vec3 before = glm::vec3(glm::inverse(camera.prev_view)[3]);
    // The camera's x axis in world space is the first row of the view's rotation.
    const glm::vec3 right(camera.view[0][0], camera.view[1][0], camera.view[2][0]);
    const float sideways = glm::dot(now - before, glm::normalize(right));
    if (!std::isfinite(sideways) || std::abs(sideways) <= dead_zone * std::abs(rig.ipd))
        return previous;
    return sideways > 0.0f ? Eye::Right : Eye::Left;
}

}  // namespace reprise::stereo
