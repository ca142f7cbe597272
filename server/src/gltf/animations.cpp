// glTF loader, animations: samplers (times, interpolation, values) and channels.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

#include "internal.hpp"

namespace reprise::server::gltf_loader {

namespace {

Status interpolation_of(const Gltf& g, const std::string& field, const std::string& name,
                        Interpolation& out) {
    if (name == "LINEAR")
        out = Interpolation::Linear;
    else if (name == "STEP")
        out = Interpolation::Step;
    else if (name == "CUBICSPLINE")
        out = Interpolation::CubicSpline;
    else
        return g.fail(field, "\"" + name + "\" is not LINEAR, STEP or CUBICSPLINE");
    return ok();
}

// Keyframe times must not decrease; repeated times (a jump) are nudged apart by one ulp so the
// Scene's times increase strictly.
Status make_increasing(const Gltf& g, const std::string& field, std::vector<float>& times) {
    float previous = times.empty() ? 0.0f : times[0];
    for (size_t k = 1; k < times.size(); ++k) {
        const float original = times[k];
        if (original < previous)
            return g.fail(field, "time " + std::to_string(original) + " at key " +
                                     std::to_string(k) + " is before the previous key's " +
                                     std::to_string(previous));
        if (times[k] <= times[k - 1])
            times[k] = std::nextafter(times[k - 1], std::numeric_limits<float>::infinity());
        previous = original;
    }
    return ok();
}

void normalize_rotations(std::vector<float>& values, Interpolation interpolation) {
    const bool spline = interpolation == Interpolation::CubicSpline;
    const size_t stride = spline ? 12 : 4;
    for (size_t k = spline ? 4 : 0; k + 4 <= values.size(); k += stride) {
        const glm::vec4 q(values[k], values[k + 1], values[k + 2], values[k + 3]);
        const float length = glm::length(q);
        if (length > 1e-12f)
            for (size_t c = 0; c < 4; ++c) values[k + c] /= length;
    }
}

Status check_rotations(const Gltf& g, const std::string& field, const std::vector<float>& values,
                       Interpolation interpolation) {
    const bool spline = interpolation == Interpolation::CubicSpline;
    const size_t stride = spline ? 12 : 4;
    for (size_t k = spline ? 4 : 0; k + 4 <= values.size(); k += stride) {
        const float length =
            glm::length(glm::vec4(values[k], values[k + 1], values[k + 2], values[k + 3]));
        if (!(length > 1e-12f))
            return g.fail(field, "key " + std::to_string(k / stride) + " is a zero quaternion");
    }
    return ok();
}

struct ChannelTarget {
    AnimatedPath path = AnimatedPath::Translation;
    int type = TINYGLTF_TYPE_VEC3;
    unsigned kinds = F32;
    int components = 3;
};

// False in `known` for paths reprise does not animate (e.g. KHR_animation_pointer's).
Status target_of(const Gltf& g, const std::string& field, const std::string& path, const Node& node,
                 const Scene& scene, ChannelTarget& out, bool& known) {
    const unsigned normalized = F32 | I8N | U8N | I16N | U16N;
    known = true;
    if (path == "translation")
        out = {AnimatedPath::Translation, TINYGLTF_TYPE_VEC3, F32, 3};
    else if (path == "scale")
        out = {AnimatedPath::Scale, TINYGLTF_TYPE_VEC3, F32, 3};
    else if (path == "rotation")
        out = {AnimatedPath::Rotation, TINYGLTF_TYPE_VEC4, normalized, 4};
    else if (path == "weights")
        out = {AnimatedPath::Weights, TINYGLTF_TYPE_SCALAR, normalized, 0};
    else
        known = false;
    if (!known) return ok();
    if (out.path != AnimatedPath::Weights && node.has_matrix)
        return g.fail(field + ".target.path",
                      path + " of a node that has a matrix (glTF 2.0 §3.11)");
    if (out.path == AnimatedPath::Weights) {
        out.components = node.mesh >= 0 ? int(scene.meshes[size_t(node.mesh)].weights.size()) : 0;
        if (out.components == 0)
            return g.fail(field + ".target.path", "weights of a node without morph targets");
    }
    return ok();
}

Status convert_channel(const Gltf& g, const tg::Animation& animation, const std::string& prefix,
                       size_t index, const Scene& scene, AnimationChannel& out, bool& keep) {
    const tg::AnimationChannel& channel = animation.channels[index];
    const std::string field = prefix + "." + item("channels", index);
    REPRISE_TRY(
        check_index(g, field + ".sampler", channel.sampler, animation.samplers.size(), "samplers"));
    keep = channel.target_node >= 0;  // no node: the target is an extension's
    if (!keep) return ok();
    REPRISE_TRY(
        check_index(g, field + ".target.node", channel.target_node, scene.nodes.size(), "nodes"));
    ChannelTarget target;
    REPRISE_TRY(target_of(g, field, channel.target_path, scene.nodes[size_t(channel.target_node)],
                          scene, target, keep));
    if (!keep) return ok();
    const tg::AnimationSampler& sampler = animation.samplers[size_t(channel.sampler)];
    const std::string sampler_field = prefix + "." + item("samplers", size_t(channel.sampler));
    REPRISE_TRY(interpolation_of(g, sampler_field + ".interpolation", sampler.interpolation,
                                 out.interpolation));
    REPRISE_TRY(read_floats(g, sampler.input, {sampler_field + ".input", TINYGLTF_TYPE_SCALAR, F32},
                            out.times));
    REPRISE_TRY(make_increasing(g, sampler_field + ".input", out.times));
    const bool spline = out.interpolation == Interpolation::CubicSpline;
    if (spline && out.times.size() < 2)
        return g.fail(sampler_field + ".input", "CUBICSPLINE needs at least 2 keys");
    const std::string output = sampler_field + ".output";
    REPRISE_TRY(read_floats(g, sampler.output, {output, target.type, target.kinds}, out.values));
    const size_t expected = out.times.size() * size_t(target.components) * (spline ? 3 : 1);
    if (out.values.size() != expected)
        return g.fail(output, count_of(out.values.size(), "values") + ", expected " +
                                  std::to_string(expected) + " for " +
                                  count_of(out.times.size(), "keys"));
    if (target.path == AnimatedPath::Rotation) {
        REPRISE_TRY(check_rotations(g, output, out.values, out.interpolation));
        normalize_rotations(out.values, out.interpolation);
    }
    out.node = channel.target_node;
    out.path = target.path;
    out.components = target.components;
    return ok();
}

}  // namespace

Status convert_animation(const Gltf& g, size_t index, const Scene& scene, Animation& out) {
    const tg::Animation& animation = g.model.animations[index];
    out.name = animation.name;
    for (size_t c = 0; c < animation.channels.size(); ++c) {
        AnimationChannel channel;
        bool keep = false;
        REPRISE_TRY(
            convert_channel(g, animation, item("animations", index), c, scene, channel, keep));
        if (keep) out.channels.push_back(std::move(channel));
    }
    return ok();
}

}  // namespace reprise::server::gltf_loader
