#pragma once
// Scenes built in code, each stressing one thing; no asset files needed.
#include <string>
#include <vector>

#include "reprise/server/camera_path.hpp"
#include "reprise/server/gltf.hpp"

namespace reprise::server {

struct SceneInfo {
    const char* name;
    const char* stresses;
};

// pan (default), fence, crossing, specular, fast, cut, mirror; courtyard, stroll and shadows
// (heavy shading).
const std::vector<SceneInfo>& builtin_scenes();

// A built-in scene by name, or a .gltf/.glb file, with the camera path it comes with.
Status load_scene(const std::string& name_or_file, Scene& scene, CameraPath& camera,
                  const GltfOptions& gltf = {});

}  // namespace reprise::server
