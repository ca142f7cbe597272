#pragma once
// What the glTF loader's parts share (server/src/gltf/): the model being converted, accessor use
// and reading, and the conversions the whole-model pass calls. tinygltf parses; every range,
// type, value and link that the renderer will trust is checked in these files.
#include <tiny_gltf.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "reprise/core/status.hpp"
#include "reprise/server/scene.hpp"

namespace reprise::server::gltf_loader {

namespace tg = tinygltf;

inline std::string item(std::string_view array, size_t index) {
    return std::string(array) + "[" + std::to_string(index) + "]";
}

inline std::string count_of(size_t n, std::string_view what) {
    return std::to_string(n) + " " + std::string(what);
}

// The loaded model and the file name every message starts with.
struct Gltf {
    std::string file;
    const tg::Model& model;
    std::string warnings;    // tinygltf's, quoted when an image failed to load
    bool quantized = false;  // KHR_mesh_quantization widens the allowed attribute types

    Status fail(const std::string& field, const std::string& problem) const {
        return Status::error(file + ": " + field + ": " + problem);
    }
};

inline Status check_index(const Gltf& g, const std::string& field, int index, size_t size,
                          std::string_view array) {
    if (index >= 0 && size_t(index) < size) return ok();
    return g.fail(
        field, "index " + std::to_string(index) + " out of range (" + count_of(size, array) + ")");
}

// ---------------------------------------------------------------------------------------------
// Accessors (accessors.cpp)

// An accessor's component type together with its `normalized` flag, as one bit.
constexpr unsigned F32 = 1u << 0;
constexpr unsigned U8 = 1u << 1;
constexpr unsigned U16 = 1u << 2;
constexpr unsigned U32 = 1u << 3;
constexpr unsigned I8 = 1u << 4;
constexpr unsigned I16 = 1u << 5;
constexpr unsigned U8N = 1u << 6;
constexpr unsigned U16N = 1u << 7;
constexpr unsigned I8N = 1u << 8;
constexpr unsigned I16N = 1u << 9;
constexpr unsigned all_kinds = (1u << 10) - 1;

// How an accessor is used: where (for messages), with which type and component kinds.
struct Use {
    std::string field;
    int type = TINYGLTF_TYPE_SCALAR;
    unsigned kinds = F32;
};

// Every buffer view lies inside its buffer.
Status check_buffer_views(const Gltf& g);

// All values of an accessor as floats, flattened; every value must be finite.
Status read_floats(const Gltf& g, int index, const Use& use, std::vector<float>& out);
Status read_uints(const Gltf& g, int index, const Use& use, std::vector<uint32_t>& out);

template <class V>
std::vector<V> group(const std::vector<float>& flat) {
    static_assert(sizeof(V) % sizeof(float) == 0);
    std::vector<V> out(flat.size() * sizeof(float) / sizeof(V));
    std::memcpy(static_cast<void*>(out.data()), flat.data(), out.size() * sizeof(V));
    return out;
}

template <class V>
Status read_vectors(const Gltf& g, int index, const Use& use, std::vector<V>& out) {
    REPRISE_ASSERT(size_t(tg::GetNumComponentsInType(uint32_t(use.type))) * sizeof(float) ==
                   sizeof(V));
    std::vector<float> flat;
    REPRISE_TRY(read_floats(g, index, use, flat));
    out = group<V>(flat);
    return ok();
}

// ---------------------------------------------------------------------------------------------
// Textures and materials (materials.cpp)

// Scene textures are only the ones materials use; `remap` maps glTF texture indices to them.
struct TextureTable {
    std::vector<Texture> textures;
    std::vector<int> remap;
};

Status convert_material(const Gltf& g, size_t index, TextureTable& table, Material& out);

// ---------------------------------------------------------------------------------------------
// Meshes (meshes.cpp)

// `skipped` counts POINTS and LINES primitives, which are left out.
Status convert_mesh(const Gltf& g, size_t index, const std::vector<Material>& materials, Mesh& out,
                    size_t& skipped);

// ---------------------------------------------------------------------------------------------
// Skins, cameras, nodes (nodes.cpp)

Status convert_skin(const Gltf& g, size_t index, Skin& out);
Status convert_camera(const Gltf& g, size_t index, CameraModel& out);
Status convert_node(const Gltf& g, size_t index, const Scene& scene, Node& out);
// Every node has at most one parent and the children lists are acyclic. `parent` gets -1 for
// roots.
Status check_hierarchy(const Gltf& g, const std::vector<Node>& nodes, std::vector<int>& parent);
Status choose_roots(const Gltf& g, const std::vector<int>& parent, std::vector<int>& roots,
                    std::string& name);
bool draws_triangles(const Scene& scene);

// ---------------------------------------------------------------------------------------------
// Animations (animations.cpp)

Status convert_animation(const Gltf& g, size_t index, const Scene& scene, Animation& out);

}  // namespace reprise::server::gltf_loader
