#include "reprise/server/animation.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace reprise::server {

double animation_duration(const Scene& scene) {
    double duration = 0.0;
    for (const Animation& a : scene.animations)
        for (const AnimationChannel& c : a.channels)
            if (!c.times.empty()) duration = std::max(duration, double(c.times.back()));
    return duration;
}

namespace {

// Transforms normals like transpose(inverse(m)) up to scale, and stays finite when m is
// singular (a zero scale is legal glTF).
glm::mat3 normal_matrix(const glm::mat3& m) {
    glm::mat3 cofactor(glm::cross(m[1], m[2]), glm::cross(m[2], m[0]), glm::cross(m[0], m[1]));
    return glm::determinant(m) < 0.0f ? -cofactor : cofactor;  // mirrors keep outward normals
}

struct Local {
    glm::vec3 translation;
    glm::quat rotation;
    glm::vec3 scale;
};

// Keyframe value k of a channel (skipping the tangents of cubic splines).
const float* key_value(const AnimationChannel& c, std::size_t k, int part = 1) {
    std::size_t stride = c.interpolation == Interpolation::CubicSpline ? 3 : 1;
    std::size_t slot = c.interpolation == Interpolation::CubicSpline ? k * stride + part : k;
    return c.values.data() + slot * c.components;
}

// Samples a channel at time t into `out` (c.components floats).
void sample(const AnimationChannel& c, float t, float* out) {
    const int n = c.components;
    const std::size_t keys = c.times.size();
    auto copy = [&](const float* v) { std::copy(v, v + n, out); };
    if (t <= c.times.front() || keys == 1) return copy(key_value(c, 0));
    if (t >= c.times.back()) return copy(key_value(c, keys - 1));
    std::size_t k = std::upper_bound(c.times.begin(), c.times.end(), t) - c.times.begin() - 1;
    float t0 = c.times[k], t1 = c.times[k + 1];
    float dt = t1 - t0;
    float s = dt > 0 ? (t - t0) / dt : 0.0f;
    const float* a = key_value(c, k);
    const float* b = key_value(c, k + 1);
    switch (c.interpolation) {
        case Interpolation::Step:
            return copy(a);
        case Interpolation::Linear:
            if (c.path == AnimatedPath::Rotation) {
                glm::quat qa(a[3], a[0], a[1], a[2]), qb(b[3], b[0], b[1], b[2]);
                glm::quat q = glm::slerp(qa, qb, s);
                out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
                return;
            }
            for (int i = 0; i < n; ++i) out[i] = a[i] + s * (b[i] - a[i]);
            return;
        case Interpolation::CubicSpline: {
            const float* out_tangent = key_value(c, k, 2);
            const float* in_tangent = key_value(c, k + 1, 0);
            float s2 = s * s, s3 = s2 * s;
            float h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s;
            float h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
            for (int i = 0; i < n; ++i)
                out[i] =
                    h00 * a[i] + h10 * dt * out_tangent[i] + h01 * b[i] + h11 * dt * in_tangent[i];
            return;
        }
    }
}

glm::mat4 local_matrix(const Node& node, const Local& l, bool animated) {
    if (node.has_matrix && !animated) return node.matrix;
    return glm::translate(glm::mat4(1.0f), l.translation) * glm::mat4_cast(l.rotation) *
           glm::scale(glm::mat4(1.0f), l.scale);
}

}  // namespace

void evaluate_pose(const Scene& scene, double time, Pose& pose) {
    const std::size_t count = scene.nodes.size();
    std::vector<Local> local(count);
    std::vector<char> animated(count, 0);
    pose.weights.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
        const Node& n = scene.nodes[i];
        local[i] = {n.translation, n.rotation, n.scale};
        if (!n.weights.empty())
            pose.weights[i] = n.weights;
        else if (n.mesh >= 0)
            pose.weights[i] = scene.meshes[n.mesh].weights;
        else
            pose.weights[i].clear();
    }
    double duration = animation_duration(scene);
    // Loop after the end; before the start, keys clamp (or extend, for keys at negative times).
    float t = float(duration > 0 && time > duration ? std::fmod(time, duration) : time);
    float value[64];
    std::vector<float> many;
    for (const Animation& a : scene.animations) {
        for (const AnimationChannel& c : a.channels) {
            if (c.times.empty()) continue;
            float* out = value;
            if (c.components > 64) {
                many.resize(c.components);
                out = many.data();
            }
            sample(c, t, out);
            Local& l = local[c.node];
            animated[c.node] = 1;
            switch (c.path) {
                case AnimatedPath::Translation:
                    l.translation = {out[0], out[1], out[2]};
                    break;
                case AnimatedPath::Scale:
                    l.scale = {out[0], out[1], out[2]};
                    break;
                case AnimatedPath::Rotation:
                    l.rotation = glm::normalize(glm::quat(out[3], out[0], out[1], out[2]));
                    break;
                case AnimatedPath::Weights: {
                    auto& w = pose.weights[c.node];
                    w.assign(out, out + c.components);
                    break;
                }
            }
        }
    }
    pose.world.assign(count, glm::mat4(1.0f));
    // The loader guarantees an acyclic graph with one parent per node.
    std::vector<int> stack;
    std::vector<char> placed(count, 0);
    auto visit_from = [&](int root, const glm::mat4& parent) {
        pose.world[root] = parent * local_matrix(scene.nodes[root], local[root], animated[root]);
        placed[root] = 1;
        stack.assign(1, root);
        while (!stack.empty()) {
            int n = stack.back();
            stack.pop_back();
            for (int child : scene.nodes[n].children) {
                pose.world[child] =
                    pose.world[n] * local_matrix(scene.nodes[child], local[child], animated[child]);
                placed[child] = 1;
                stack.push_back(child);
            }
        }
    };
    for (int root : scene.roots) visit_from(root, glm::mat4(1.0f));
    // Nodes outside the drawn hierarchy (e.g. skeletons referenced only by skins).
    std::vector<char> has_parent(count, 0);
    for (const Node& n : scene.nodes)
        for (int child : n.children) has_parent[child] = 1;
    for (std::size_t i = 0; i < count; ++i)
        if (!placed[i] && !has_parent[i]) visit_from(int(i), glm::mat4(1.0f));
}

void pose_vertices(const Scene& scene, const Pose& pose, int node, const Primitive& primitive,
                   std::vector<glm::vec3>& positions, std::vector<glm::vec3>& normals) {
    const Node& n = scene.nodes[node];
    const std::size_t count = primitive.positions.size();
    positions = primitive.positions;
    normals = primitive.normals;
    const std::vector<float>& weights = pose.weights[node];
    for (std::size_t t = 0; t < primitive.targets.size() && t < weights.size(); ++t) {
        float w = weights[t];
        if (w == 0.0f) continue;
        const MorphTarget& target = primitive.targets[t];
        for (std::size_t v = 0; v < target.positions.size(); ++v)
            positions[v] += w * target.positions[v];
        for (std::size_t v = 0; v < target.normals.size() && v < normals.size(); ++v)
            normals[v] += w * target.normals[v];
    }
    const bool skinned = n.skin >= 0 && !primitive.joints.empty() && !primitive.weights.empty();
    if (!skinned) {
        const glm::mat4& m = pose.world[node];
        const glm::mat3 to_world = normal_matrix(glm::mat3(m));
        for (glm::vec3& p : positions) p = glm::vec3(m * glm::vec4(p, 1.0f));
        for (glm::vec3& v : normals) v = to_world * v;
        return;
    }
    const Skin& skin = scene.skins[n.skin];
    std::vector<glm::mat4> joint(skin.joints.size());
    for (std::size_t j = 0; j < joint.size(); ++j)
        joint[j] = pose.world[skin.joints[j]] * skin.inverse_bind[j];
    for (std::size_t v = 0; v < count; ++v) {
        const glm::u16vec4 ji = primitive.joints[v];
        const glm::vec4 wi = primitive.weights[v];
        glm::mat4 m =
            wi.x * joint[ji.x] + wi.y * joint[ji.y] + wi.z * joint[ji.z] + wi.w * joint[ji.w];
        positions[v] = glm::vec3(m * glm::vec4(positions[v], 1.0f));
        if (v < normals.size()) normals[v] = normal_matrix(glm::mat3(m)) * normals[v];
    }
}

Bounds scene_bounds(const Scene& scene, const Pose& pose) {
    Bounds b;
    std::vector<glm::vec3> positions, normals;
    for (std::size_t i = 0; i < scene.nodes.size(); ++i) {
        if (scene.nodes[i].mesh < 0) continue;
        for (const Primitive& p : scene.meshes[scene.nodes[i].mesh].primitives) {
            pose_vertices(scene, pose, int(i), p, positions, normals);
            for (const glm::vec3& v : positions) {
                b.min = b.empty ? v : glm::min(b.min, v);
                b.max = b.empty ? v : glm::max(b.max, v);
                b.empty = false;
            }
        }
    }
    return b;
}

}  // namespace reprise::server
