// glTF loader, meshes: attribute rules (glTF 2.0 §3.7.2.1, widened by KHR_mesh_quantization),
// primitives, indices, normals, texture coordinates, skinning and morph targets.
#include <cmath>
#include <glm/geometric.hpp>
#include <map>
#include <numeric>

#include "internal.hpp"

namespace reprise::server::gltf_loader {

namespace {

unsigned position_kinds(const Gltf& g) {
    return F32 | (g.quantized ? I8 | I8N | U8 | U8N | I16 | I16N | U16 | U16N : 0);
}

unsigned normal_kinds(const Gltf& g) { return F32 | (g.quantized ? I8N | I16N : 0); }

unsigned texcoord_kinds(const Gltf& g) {
    return F32 | U8N | U16N | (g.quantized ? I8 | I8N | U8 | I16 | I16N | U16 : 0);
}

unsigned target_kinds(const Gltf& g) { return F32 | (g.quantized ? I8 | I8N | I16 | I16N : 0); }

int attribute(const std::map<std::string, int>& attributes, const std::string& name) {
    const auto it = attributes.find(name);
    return it == attributes.end() ? -1 : it->second;
}

Status check_count(const Gltf& g, const std::string& field, size_t count, size_t vertices) {
    if (count == vertices) return ok();
    return g.fail(field, "count " + std::to_string(count) + " differs from the POSITION count " +
                             std::to_string(vertices));
}

// Unit normals; false when one cannot be normalised (zero length).
bool normalize_all(std::vector<glm::vec3>& normals) {
    for (glm::vec3& n : normals) {
        const float length = glm::length(n);
        if (!(length > 1e-12f) || !std::isfinite(length)) return false;
        n /= length;
    }
    return true;
}

enum class Topology { Triangles, Strip, Fan, Unsupported };

Status topology_of(const Gltf& g, const std::string& field, int mode, Topology& out) {
    switch (mode) {
        case TINYGLTF_MODE_TRIANGLES:
            out = Topology::Triangles;
            return ok();
        case TINYGLTF_MODE_TRIANGLE_STRIP:
            out = Topology::Strip;
            return ok();
        case TINYGLTF_MODE_TRIANGLE_FAN:
            out = Topology::Fan;
            return ok();
        case TINYGLTF_MODE_POINTS:
        case TINYGLTF_MODE_LINE:
        case TINYGLTF_MODE_LINE_LOOP:
        case TINYGLTF_MODE_LINE_STRIP:
            out = Topology::Unsupported;
            return ok();
        default:
            return g.fail(field + ".mode", std::to_string(mode) + " is not a glTF primitive mode");
    }
}

// Strips and fans into a triangle list, in the winding order glTF 2.0 §3.7.2.1 defines.
std::vector<uint32_t> to_triangle_list(const std::vector<uint32_t>& v, Topology topology) {
    if (topology == Topology::Triangles) return v;
    std::vector<uint32_t> list;
    if (v.size() < 3) return list;
    list.reserve((v.size() - 2) * 3);
    for (size_t i = 0; i + 2 < v.size(); ++i) {
        if (topology == Topology::Strip && i % 2 == 0)
            list.insert(list.end(), {v[i], v[i + 1], v[i + 2]});
        if (topology == Topology::Strip && i % 2 == 1)
            list.insert(list.end(), {v[i], v[i + 2], v[i + 1]});
        if (topology == Topology::Fan) list.insert(list.end(), {v[i + 1], v[i + 2], v[0]});
    }
    return list;
}

Status read_indices(const Gltf& g, const tg::Primitive& p, const std::string& field,
                    size_t vertices, Topology topology, std::vector<uint32_t>& out) {
    std::vector<uint32_t> raw;
    if (p.indices >= 0) {
        REPRISE_TRY(read_uints(g, p.indices,
                               {field + ".indices", TINYGLTF_TYPE_SCALAR, U8 | U16 | U32}, raw));
        for (const uint32_t index : raw)
            if (index >= vertices)
                return g.fail(field + ".indices", "index " + std::to_string(index) +
                                                      " >= vertex count " +
                                                      std::to_string(vertices));
    } else {
        raw.resize(vertices);
        std::iota(raw.begin(), raw.end(), 0u);
    }
    if (topology == Topology::Triangles && raw.size() % 3 != 0)
        return g.fail(p.indices >= 0 ? field + ".indices" : field + ".attributes.POSITION",
                      std::to_string(raw.size()) + " vertices do not make whole TRIANGLES");
    out = to_triangle_list(raw, topology);
    return ok();
}

Status read_normals(const Gltf& g, const tg::Primitive& p, const std::string& field,
                    size_t vertices, std::vector<glm::vec3>& out) {
    const int index = attribute(p.attributes, "NORMAL");
    if (index < 0) return ok();
    const std::string name = field + ".attributes.NORMAL";
    REPRISE_TRY(read_vectors(g, index, {name, TINYGLTF_TYPE_VEC3, normal_kinds(g)}, out));
    REPRISE_TRY(check_count(g, name, out.size(), vertices));
    if (!normalize_all(out)) out.clear();  // zero normals: the renderer computes flat ones
    return ok();
}

Status read_texcoords(const Gltf& g, const tg::Primitive& p, const std::string& field,
                      size_t vertices, int set, std::vector<glm::vec2>& out) {
    const std::string attr = "TEXCOORD_" + std::to_string(set);
    const int index = attribute(p.attributes, attr);
    if (index < 0) return ok();
    const std::string name = field + ".attributes." + attr;
    REPRISE_TRY(read_vectors(g, index, {name, TINYGLTF_TYPE_VEC2, texcoord_kinds(g)}, out));
    return check_count(g, name, out.size(), vertices);
}

Status normalize_weights(const Gltf& g, const std::string& field, std::vector<glm::vec4>& weights) {
    for (size_t i = 0; i < weights.size(); ++i) {
        glm::vec4& w = weights[i];
        const float sum = w.x + w.y + w.z + w.w;
        if (w.x < 0 || w.y < 0 || w.z < 0 || w.w < 0 || !(sum > 0.0f))
            return g.fail(field, "vertex " + std::to_string(i) +
                                     " has negative weights or weights that sum to 0");
        w /= sum;
    }
    return ok();
}

Status read_skinning(const Gltf& g, const tg::Primitive& p, const std::string& field,
                     size_t vertices, Primitive& out) {
    const int joints = attribute(p.attributes, "JOINTS_0");
    const int weights = attribute(p.attributes, "WEIGHTS_0");
    if (joints < 0 && weights < 0) return ok();
    if (joints < 0 || weights < 0)
        return g.fail(field + ".attributes", "JOINTS_0 and WEIGHTS_0 must come together");
    const std::string joints_name = field + ".attributes.JOINTS_0";
    const std::string weights_name = field + ".attributes.WEIGHTS_0";
    std::vector<uint32_t> flat;
    REPRISE_TRY(read_uints(g, joints, {joints_name, TINYGLTF_TYPE_VEC4, U8 | U16}, flat));
    REPRISE_TRY(check_count(g, joints_name, flat.size() / 4, vertices));
    out.joints.resize(vertices);
    for (size_t i = 0; i < vertices; ++i)
        out.joints[i] =
            glm::u16vec4(flat[4 * i], flat[4 * i + 1], flat[4 * i + 2], flat[4 * i + 3]);
    REPRISE_TRY(read_vectors(g, weights, {weights_name, TINYGLTF_TYPE_VEC4, F32 | U8N | U16N},
                             out.weights));
    REPRISE_TRY(check_count(g, weights_name, out.weights.size(), vertices));
    return normalize_weights(g, weights_name, out.weights);
}

Status read_targets(const Gltf& g, const tg::Primitive& p, const std::string& field,
                    size_t vertices, bool keep_normals, std::vector<MorphTarget>& out) {
    out.resize(p.targets.size());
    for (size_t t = 0; t < p.targets.size(); ++t) {
        const std::string name = field + "." + item("targets", t);
        const int positions = attribute(p.targets[t], "POSITION");
        const int normals = attribute(p.targets[t], "NORMAL");
        if (positions >= 0) {
            REPRISE_TRY(read_vectors(g, positions,
                                     {name + ".POSITION", TINYGLTF_TYPE_VEC3, target_kinds(g)},
                                     out[t].positions));
            REPRISE_TRY(check_count(g, name + ".POSITION", out[t].positions.size(), vertices));
        }
        if (normals >= 0) {
            REPRISE_TRY(read_vectors(g, normals,
                                     {name + ".NORMAL", TINYGLTF_TYPE_VEC3, target_kinds(g)},
                                     out[t].normals));
            REPRISE_TRY(check_count(g, name + ".NORMAL", out[t].normals.size(), vertices));
            if (!keep_normals) out[t].normals.clear();
        }
    }
    return ok();
}

// A textured material reads a UV set; the primitive must have it.
Status check_material(const Gltf& g, const tg::Primitive& p, const std::string& field,
                      const std::vector<Material>& materials, const Primitive& out) {
    if (p.material < 0) return ok();
    REPRISE_TRY(check_index(g, field + ".material", p.material, materials.size(), "materials"));
    const Material& material = materials[size_t(p.material)];
    if (material.base_color_texture < 0) return ok();
    const auto& uv = material.texcoord == 0 ? out.uv0 : out.uv1;
    if (!uv.empty()) return ok();
    return g.fail(field, "materials[" + std::to_string(p.material) +
                             "] is textured through TEXCOORD_" + std::to_string(material.texcoord) +
                             ", which the primitive lacks");
}

Status convert_primitive(const Gltf& g, const tg::Primitive& p, const std::string& field,
                         const std::vector<Material>& materials, Primitive& out, bool& skipped) {
    Topology topology = Topology::Unsupported;
    REPRISE_TRY(topology_of(g, field, p.mode, topology));
    skipped = topology == Topology::Unsupported;
    if (skipped) return ok();
    const int positions = attribute(p.attributes, "POSITION");
    if (positions < 0) return g.fail(field + ".attributes", "no POSITION");
    REPRISE_TRY(read_vectors(
        g, positions, {field + ".attributes.POSITION", TINYGLTF_TYPE_VEC3, position_kinds(g)},
        out.positions));
    const size_t vertices = out.positions.size();
    REPRISE_TRY(read_normals(g, p, field, vertices, out.normals));
    REPRISE_TRY(read_texcoords(g, p, field, vertices, 0, out.uv0));
    REPRISE_TRY(read_texcoords(g, p, field, vertices, 1, out.uv1));
    REPRISE_TRY(read_skinning(g, p, field, vertices, out));
    REPRISE_TRY(read_targets(g, p, field, vertices, !out.normals.empty(), out.targets));
    REPRISE_TRY(read_indices(g, p, field, vertices, topology, out.indices));
    REPRISE_TRY(check_material(g, p, field, materials, out));
    out.material = p.material;
    return ok();
}

}  // namespace

Status convert_mesh(const Gltf& g, size_t index, const std::vector<Material>& materials, Mesh& out,
                    size_t& skipped) {
    const tg::Mesh& mesh = g.model.meshes[index];
    const std::string field = item("meshes", index);
    if (mesh.primitives.empty())
        return g.fail(field + ".primitives", "none (at least one is required)");
    const size_t targets = mesh.primitives[0].targets.size();
    out.name = mesh.name;
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
        const std::string name = field + "." + item("primitives", p);
        if (mesh.primitives[p].targets.size() != targets)
            return g.fail(name + ".targets",
                          count_of(mesh.primitives[p].targets.size(), "morph targets") +
                              ", but primitives[0] has " + std::to_string(targets));
        Primitive primitive;
        bool unsupported = false;
        REPRISE_TRY(
            convert_primitive(g, mesh.primitives[p], name, materials, primitive, unsupported));
        if (unsupported)
            ++skipped;
        else
            out.primitives.push_back(std::move(primitive));
    }
    if (!mesh.weights.empty() && mesh.weights.size() != targets)
        return g.fail(field + ".weights", count_of(mesh.weights.size(), "weights") + " for " +
                                              count_of(targets, "morph targets"));
    out.weights.assign(targets, 0.0f);
    for (size_t w = 0; w < mesh.weights.size(); ++w) {
        if (!std::isfinite(mesh.weights[w])) return g.fail(field + ".weights", "not finite");
        out.weights[w] = float(mesh.weights[w]);
    }
    return ok();
}

}  // namespace reprise::server::gltf_loader
