// glTF loader, skins, cameras and nodes: transforms, the node graph (one parent, no cycles) and
// the scene's roots.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <numbers>

#include "internal.hpp"

namespace reprise::server::gltf_loader {

Status convert_skin(const Gltf& g, size_t index, Skin& out) {
    const tg::Skin& skin = g.model.skins[index];
    const std::string field = item("skins", index);
    if (skin.joints.empty()) return g.fail(field + ".joints", "empty");
    for (size_t j = 0; j < skin.joints.size(); ++j)
        REPRISE_TRY(check_index(g, field + "." + item("joints", j), skin.joints[j],
                                g.model.nodes.size(), "nodes"));
    if (skin.skeleton >= 0)
        REPRISE_TRY(
            check_index(g, field + ".skeleton", skin.skeleton, g.model.nodes.size(), "nodes"));
    out.joints = skin.joints;
    if (skin.inverseBindMatrices < 0) {
        out.inverse_bind.assign(skin.joints.size(), glm::mat4(1.0f));
        return ok();
    }
    const std::string name = field + ".inverseBindMatrices";
    REPRISE_TRY(read_vectors(g, skin.inverseBindMatrices, {name, TINYGLTF_TYPE_MAT4, F32},
                             out.inverse_bind));
    if (out.inverse_bind.size() < skin.joints.size())
        return g.fail(name, count_of(out.inverse_bind.size(), "matrices") + " for " +
                                count_of(skin.joints.size(), "joints"));
    out.inverse_bind.resize(skin.joints.size());
    return ok();
}

namespace {

bool finite_positive(double v) { return std::isfinite(v) && v > 0.0; }

Status convert_perspective(const Gltf& g, const std::string& field, const tg::PerspectiveCamera& c,
                           CameraModel& out) {
    if (!finite_positive(c.yfov) || c.yfov >= std::numbers::pi)
        return g.fail(field + ".yfov", std::to_string(c.yfov) + " is not in (0, pi)");
    if (!finite_positive(c.znear))
        return g.fail(field + ".znear", std::to_string(c.znear) + " is not > 0");
    if (c.zfar != 0.0 && !(std::isfinite(c.zfar) && c.zfar > c.znear))
        return g.fail(field + ".zfar", std::to_string(c.zfar) + " is not > znear");
    if (c.aspectRatio != 0.0 && !finite_positive(c.aspectRatio))
        return g.fail(field + ".aspectRatio", std::to_string(c.aspectRatio) + " is not > 0");
    out.perspective = true;
    out.yfov = float(c.yfov);
    out.aspect = float(c.aspectRatio);
    out.znear = float(c.znear);
    out.zfar = float(c.zfar);
    return ok();
}

Status convert_orthographic(const Gltf& g, const std::string& field,
                            const tg::OrthographicCamera& c, CameraModel& out) {
    if (!std::isfinite(c.xmag) || c.xmag == 0.0)
        return g.fail(field + ".xmag", "is 0 or not finite");
    if (!std::isfinite(c.ymag) || c.ymag == 0.0)
        return g.fail(field + ".ymag", "is 0 or not finite");
    if (!std::isfinite(c.znear) || c.znear < 0.0)
        return g.fail(field + ".znear", std::to_string(c.znear) + " is not >= 0");
    if (!std::isfinite(c.zfar) || c.zfar <= c.znear)
        return g.fail(field + ".zfar", std::to_string(c.zfar) + " is not > znear");
    out.perspective = false;
    out.xmag = float(c.xmag);
    out.ymag = float(c.ymag);
    out.znear = float(c.znear);
    out.zfar = float(c.zfar);
    return ok();
}

}  // namespace

Status convert_camera(const Gltf& g, size_t index, CameraModel& out) {
    const tg::Camera& camera = g.model.cameras[index];
    const std::string field = item("cameras", index);
    if (camera.type == "perspective")
        return convert_perspective(g, field + ".perspective", camera.perspective, out);
    if (camera.type == "orthographic")
        return convert_orthographic(g, field + ".orthographic", camera.orthographic, out);
    return g.fail(field + ".type",
                  "\"" + camera.type + "\" is neither perspective nor orthographic");
}

namespace {

Status read_numbers(const Gltf& g, const std::string& field, const std::vector<double>& in,
                    size_t size, float* out) {
    if (in.empty()) return ok();
    if (in.size() != size)
        return g.fail(field, count_of(in.size(), "values") + ", expected " + std::to_string(size));
    for (size_t i = 0; i < size; ++i) {
        if (!std::isfinite(in[i]))
            return g.fail(field, "value " + std::to_string(i) + " is not finite");
        out[i] = float(in[i]);
    }
    return ok();
}

Status convert_transform(const Gltf& g, const tg::Node& node, const std::string& field, Node& out) {
    REPRISE_TRY(read_numbers(g, field + ".translation", node.translation, 3,
                             glm::value_ptr(out.translation)));
    REPRISE_TRY(read_numbers(g, field + ".scale", node.scale, 3, glm::value_ptr(out.scale)));
    REPRISE_TRY(read_numbers(g, field + ".matrix", node.matrix, 16, glm::value_ptr(out.matrix)));
    out.has_matrix = !node.matrix.empty();
    float xyzw[4] = {0, 0, 0, 1};
    REPRISE_TRY(read_numbers(g, field + ".rotation", node.rotation, 4, xyzw));
    const glm::quat rotation(xyzw[3], xyzw[0], xyzw[1], xyzw[2]);
    const float length = glm::length(rotation);
    if (!(length > 1e-6f) || !std::isfinite(length))
        return g.fail(field + ".rotation", "is not a rotation (length 0)");
    out.rotation = rotation / length;
    return ok();
}

Status check_skinned_mesh(const Gltf& g, const std::string& field, const Mesh& mesh,
                          const Skin& skin) {
    for (const Primitive& p : mesh.primitives)
        for (const glm::u16vec4& j : p.joints)
            for (int c = 0; c < 4; ++c)
                if (size_t(j[c]) >= skin.joints.size())
                    return g.fail(field, "mesh joint " + std::to_string(j[c]) +
                                             " >= skin joint count " +
                                             std::to_string(skin.joints.size()));
    return ok();
}

}  // namespace

Status convert_node(const Gltf& g, size_t index, const Scene& scene, Node& out) {
    const tg::Node& node = g.model.nodes[index];
    const std::string field = item("nodes", index);
    out.name = node.name;
    for (size_t c = 0; c < node.children.size(); ++c)
        REPRISE_TRY(check_index(g, field + "." + item("children", c), node.children[c],
                                g.model.nodes.size(), "nodes"));
    out.children = node.children;
    REPRISE_TRY(convert_transform(g, node, field, out));
    if (node.camera >= 0)
        REPRISE_TRY(
            check_index(g, field + ".camera", node.camera, scene.cameras.size(), "cameras"));
    if (node.skin >= 0)
        REPRISE_TRY(check_index(g, field + ".skin", node.skin, scene.skins.size(), "skins"));
    if (node.mesh >= 0)
        REPRISE_TRY(check_index(g, field + ".mesh", node.mesh, scene.meshes.size(), "meshes"));
    out.camera = node.camera;
    out.skin = node.skin;
    out.mesh = node.mesh;
    if (node.mesh >= 0 && node.skin >= 0)
        REPRISE_TRY(check_skinned_mesh(g, field + ".skin", scene.meshes[size_t(node.mesh)],
                                       scene.skins[size_t(node.skin)]));
    if (node.weights.empty()) return ok();
    const size_t targets = node.mesh >= 0 ? scene.meshes[size_t(node.mesh)].weights.size() : 0;
    if (node.weights.size() != targets)
        return g.fail(field + ".weights", count_of(node.weights.size(), "weights") + " for " +
                                              count_of(targets, "morph targets") + " of its mesh");
    out.weights.resize(targets);
    return read_numbers(g, field + ".weights", node.weights, targets, out.weights.data());
}

// Every node has at most one parent and the children lists are acyclic. `parent` gets -1 for
// roots.
Status check_hierarchy(const Gltf& g, const std::vector<Node>& nodes, std::vector<int>& parent) {
    parent.assign(nodes.size(), -1);
    for (size_t i = 0; i < nodes.size(); ++i) {
        for (const int child : nodes[i].children) {
            int& p = parent[size_t(child)];
            if (p >= 0)
                return g.fail(item("nodes", size_t(child)), "is a child of both nodes[" +
                                                                std::to_string(p) + "] and nodes[" +
                                                                std::to_string(i) + "]");
            p = int(i);
        }
    }
    std::vector<bool> reached(nodes.size(), false);
    std::vector<int> stack;
    for (size_t i = 0; i < nodes.size(); ++i)
        if (parent[i] < 0) stack.push_back(int(i));
    while (!stack.empty()) {
        const int n = stack.back();
        stack.pop_back();
        reached[size_t(n)] = true;
        for (const int child : nodes[size_t(n)].children) stack.push_back(child);
    }
    for (size_t i = 0; i < nodes.size(); ++i)
        if (!reached[i])
            return g.fail(item("nodes", i),
                          "is its own ancestor (the children lists form a cycle)");
    return ok();
}

Status choose_roots(const Gltf& g, const std::vector<int>& parent, std::vector<int>& roots,
                    std::string& name) {
    if (g.model.scenes.empty()) {
        for (size_t i = 0; i < parent.size(); ++i)
            if (parent[i] < 0) roots.push_back(int(i));
        return ok();
    }
    const int index = std::max(g.model.defaultScene, 0);
    REPRISE_TRY(check_index(g, "scene", index, g.model.scenes.size(), "scenes"));
    const tg::Scene& scene = g.model.scenes[size_t(index)];
    const std::string field = item("scenes", size_t(index)) + ".nodes";
    if (scene.nodes.empty()) return g.fail(field, "empty, nothing to draw");
    std::vector<bool> listed(parent.size(), false);
    for (size_t r = 0; r < scene.nodes.size(); ++r) {
        const int node = scene.nodes[r];
        REPRISE_TRY(check_index(g, item(field, r), node, parent.size(), "nodes"));
        if (parent[size_t(node)] >= 0)
            return g.fail(item(field, r), "node " + std::to_string(node) + " is a child of nodes[" +
                                              std::to_string(parent[size_t(node)]) +
                                              "], not a root");
        if (listed[size_t(node)])
            return g.fail(item(field, r), "node " + std::to_string(node) + " is listed twice");
        listed[size_t(node)] = true;
        roots.push_back(node);
    }
    name = scene.name;
    return ok();
}

bool draws_triangles(const Scene& scene) {
    std::vector<int> stack = scene.roots;
    while (!stack.empty()) {
        const Node& node = scene.nodes[size_t(stack.back())];
        stack.pop_back();
        if (node.mesh >= 0)
            for (const Primitive& p : scene.meshes[size_t(node.mesh)].primitives)
                if (!p.indices.empty()) return true;
        stack.insert(stack.end(), node.children.begin(), node.children.end());
    }
    return false;
}

}  // namespace reprise::server::gltf_loader
