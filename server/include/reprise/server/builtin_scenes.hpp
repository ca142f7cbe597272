#pragma once
// Scenes built in code, each stressing one thing; no asset files needed.
#include <string>
#include <vector>

#include "reprise/core/image.hpp"
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

// The built-in HUD at `time` into `ui` (premultiplied RGBA, resized to width x height): a static
// panel with a crosshair, and a bar and a counter that change with every 30 Hz tick (the tick
// nearest to `time`, halves rounded up), drawn with hard pixel edges.
void draw_hud(double time, int width, int height, Image<glm::vec4>& ui);

// A built-in scene by name, or a .gltf/.glb file, with the camera path it comes with.
Status load_scene(const std::string& name_or_file, Scene& scene, CameraPath& camera,
                  const GltfOptions& gltf = {});

}  // namespace reprise::server
