#pragma once
// glTF 2.0 (.gltf with embedded or external buffers, .glb) into a Scene, through tinygltf.
#include <string>

#include "reprise/core/status.hpp"
#include "reprise/server/scene.hpp"

namespace reprise::server {

// Everything the renderer will trust is validated here: accessor and buffer-view ranges,
// index ranges, component types, finite values, an acyclic node graph with one parent per
// node, skins and animation targets, supported required extensions. A problem is one error
// naming the file and the field ("Box.gltf: accessors[3]: count 24 exceeds bufferView 1").
Status load_gltf(const std::string& path, Scene& scene);

}  // namespace reprise::server
