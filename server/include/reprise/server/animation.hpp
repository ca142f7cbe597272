#pragma once
// A Scene posed at one instant: node transforms, morph weights and skinned/morphed vertices.
#include <vector>

#include "reprise/server/scene.hpp"

namespace reprise::server {

struct Pose {
    std::vector<glm::mat4> world;             // per node, local -> world
    std::vector<std::vector<float>> weights;  // per node, morph weights of its mesh
};

// Animations play together and loop over the longest one's duration.
double animation_duration(const Scene& scene);
void evaluate_pose(const Scene& scene, double time, Pose& pose);

// World-space positions and normals of one primitive drawn by `node` in `pose`
// (morph targets, then skin or node transform).
void pose_vertices(const Scene& scene, const Pose& pose, int node, const Primitive& primitive,
                   std::vector<glm::vec3>& positions, std::vector<glm::vec3>& normals);

struct Bounds {
    glm::vec3 min{0.0f};
    glm::vec3 max{0.0f};
    bool empty = true;
};
Bounds scene_bounds(const Scene& scene, const Pose& pose);

}  // namespace reprise::server
