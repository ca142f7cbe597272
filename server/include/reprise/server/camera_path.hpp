#pragma once
// Where the camera is at each instant: built-in paths or an (animated) glTF camera.
#include <string>

#include "reprise/core/status.hpp"
#include "reprise/server/scene.hpp"

namespace reprise::server {

enum class CameraMotion { Static, Orbit, Pan, Dolly, Shake, Cut, Gltf };

struct CameraPath {
    CameraMotion motion = CameraMotion::Orbit;
    glm::vec3 target{0.0f};           // looked-at point (orbit, shake, cut)
    glm::vec3 eye{0.0f, 2.0f, 8.0f};  // start position (static, pan, dolly) and orbit radius/height
    float speed = 0.3f;               // orbit: rad/s; pan, dolly: scene units/s
    glm::vec3 direction{1.0f, 0.0f, 0.0f};  // pan/dolly direction of travel
    float shake = 0.01f;                    // handheld: rotation amplitude, radians
    float cut_time = 1.0f;                  // cut: seconds at which the second shot starts
    float cut_angle = 2.0f;                 // cut: orbit angle of the second shot, radians
    int gltf_node = -1;                     // Gltf: the node holding the camera
    CameraModel model;                      // projection
};

// "orbit", "pan:speed=2", "dolly:speed=1.5", "shake", "cut:time=0.5", "static", "gltf[:N]",
// with optional ",key=value" parameters: speed, radius, height, shake, time, angle.
// `fallback` supplies the framing (target, eye) that the spec's parameters adjust.
Status parse_camera_spec(const std::string& spec, const Scene& scene, const CameraPath& fallback,
                         CameraPath& path);

// A path framing the whole scene (an orbit around its bounds), or its first glTF camera.
CameraPath default_camera_path(const Scene& scene);

// World -> camera at time t (needs the posed scene for glTF cameras).
glm::mat4 camera_view(const CameraPath& path, const Scene& scene, double time);
// Camera -> clip for an image of width x height; zfar 0 gives an infinite far plane.
glm::mat4 camera_projection(const CameraModel& model, int width, int height);

}  // namespace reprise::server
