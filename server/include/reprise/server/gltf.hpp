#pragma once
// glTF 2.0 (.gltf with embedded or external buffers, .glb) into a Scene, through tinygltf.
#include <cstdint>
#include <span>
#include <string>

#include "reprise/core/status.hpp"
#include "reprise/server/scene.hpp"

namespace reprise::server {

// Everything the renderer will trust is validated here: accessor and buffer-view ranges,
// index ranges, component types, finite values, an acyclic node graph with one parent per
// node, skins and animation targets, supported required extensions. A problem is one error
// naming the file and the field ("Box.gltf: accessors[3]: count 24 exceeds bufferView 1").
struct GltfOptions {
    // External buffers and images (URIs that are not data: URIs) are read only from the glTF
    // file's own folder tree, compared after resolving symlinks; true lifts that for trusted
    // files (`reprise render --allow-outside-paths`).
    bool allow_outside_paths = false;
};

Status load_gltf(const std::string& path, Scene& scene, const GltfOptions& options = {});

// A .gltf or .glb held in memory; `name` starts every message. It has no folder, so it reads
// no external files: only data: URIs and the GLB's own BIN chunk.
Status load_gltf(std::span<const uint8_t> bytes, const std::string& name, Scene& scene);

}  // namespace reprise::server
