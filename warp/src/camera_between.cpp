#include <glm/gtc/matrix_access.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

#include "reprise/warp/fruc.hpp"

namespace reprise::warp {

namespace {

glm::mat4 rigid_blend(const glm::mat4& view_a, const glm::mat4& view_b, float s) {
    const glm::mat4 pose_a = glm::inverse(view_a), pose_b = glm::inverse(view_b);
    glm::quat qa = glm::quat_cast(glm::mat3(pose_a)), qb = glm::quat_cast(glm::mat3(pose_b));
    if (glm::dot(qa, qb) < 0.0f) qb = -qb;
    // glm::slerp's formula holds for s outside [0, 1] too: extrapolation at constant angular speed.
    glm::quat q = glm::normalize(glm::slerp(qa, qb, s));
    glm::vec3 position = glm::vec3(pose_a[3]) + s * (glm::vec3(pose_b[3]) - glm::vec3(pose_a[3]));
    glm::mat4 pose = glm::mat4_cast(q);
    pose[3] = glm::vec4(position, 1.0f);
    return glm::inverse(pose);
}

}  // namespace

Camera camera_between(const Camera& a, const Camera& b, float s) {
    Camera c = b;
    c.view = s == 1.0f ? b.view : s == 0.0f ? a.view : rigid_blend(a.view, b.view, s);
    c.prev_view = a.view;
    c.prev_projection = a.projection;
    c.jitter = glm::vec2(0.0f);
    c.time = a.time + double(s) * (b.time - a.time);
    return c;
}

}  // namespace reprise::warp
