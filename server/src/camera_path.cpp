#include "reprise/server/camera_path.hpp"

#include <charconv>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "reprise/server/animation.hpp"

namespace reprise::server {

namespace {

glm::mat4 look_at(glm::vec3 eye, glm::vec3 target) {
    glm::vec3 forward = glm::normalize(target - eye);
    glm::vec3 up = std::abs(forward.y) > 0.999f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
    return glm::lookAt(eye, target, up);
}

glm::mat4 orbit_view(const CameraPath& p, double angle) {
    glm::vec3 offset = p.eye - p.target;
    float radius = std::hypot(offset.x, offset.z);
    float start = std::atan2(offset.z, offset.x);
    glm::vec3 eye = p.target + glm::vec3(radius * std::cos(start + angle), offset.y,
                                         radius * std::sin(start + angle));
    return look_at(eye, p.target);
}

// Smooth, deterministic hand tremor: a few incommensurate sines per axis.
glm::vec3 tremor(double t) {
    auto wave = [t](double a, double b, double c) {
        return float(0.6 * std::sin(a * t + 0.3) + 0.3 * std::sin(b * t + 1.1) +
                     0.1 * std::sin(c * t + 2.0));
    };
    return {wave(3.1, 7.3, 13.7), wave(2.3, 5.9, 11.3), wave(1.7, 4.1, 9.7)};
}

}  // namespace

glm::mat4 camera_view(const CameraPath& p, const Scene& scene, double time) {
    switch (p.motion) {
        case CameraMotion::Static:
            return look_at(p.eye, p.target);
        case CameraMotion::Orbit:
            return orbit_view(p, p.speed * time);
        case CameraMotion::Pan:
        case CameraMotion::Dolly: {
            glm::vec3 move = glm::normalize(p.direction) * float(p.speed * time);
            return look_at(p.eye + move, p.target + move);
        }
        case CameraMotion::Shake: {
            glm::vec3 r = p.shake * tremor(time);
            glm::mat4 shake = glm::rotate(glm::mat4(1.0f), r.x, glm::vec3(1, 0, 0));
            shake = glm::rotate(shake, r.y, glm::vec3(0, 1, 0));
            shake = glm::rotate(shake, r.z, glm::vec3(0, 0, 1));
            return shake * orbit_view(p, p.speed * time);
        }
        case CameraMotion::Cut:
            return time < p.cut_time ? orbit_view(p, p.speed * time)
                                     : orbit_view(p, p.cut_angle + p.speed * time);
        case CameraMotion::Gltf: {
            Pose pose;
            evaluate_pose(scene, time, pose);
            glm::mat4 world = pose.world[p.gltf_node];
            // Cameras ignore scale: rebuild a rigid transform from the node's axes.
            glm::vec3 x = glm::normalize(glm::vec3(world[0]));
            glm::vec3 y = glm::normalize(glm::vec3(world[1]));
            glm::vec3 z = glm::normalize(glm::cross(x, y));
            y = glm::cross(z, x);
            glm::mat4 rigid(glm::vec4(x, 0), glm::vec4(y, 0), glm::vec4(z, 0), world[3]);
            return glm::inverse(rigid);
        }
    }
    return glm::mat4(1.0f);
}

glm::mat4 camera_projection(const CameraModel& m, int width, int height) {
    float aspect = m.aspect > 0 ? m.aspect : float(width) / float(height);
    if (!m.perspective) {
        float ymag = m.ymag, xmag = m.aspect > 0 ? m.xmag : m.ymag * aspect;
        return glm::ortho(-xmag, xmag, -ymag, ymag, m.znear, m.zfar);
    }
    if (m.zfar <= 0) return glm::infinitePerspective(m.yfov, aspect, m.znear);
    return glm::perspective(m.yfov, aspect, m.znear, m.zfar);
}

CameraPath default_camera_path(const Scene& scene) {
    CameraPath path;
    for (std::size_t i = 0; i < scene.nodes.size(); ++i) {
        if (scene.nodes[i].camera < 0) continue;
        path.motion = CameraMotion::Gltf;
        path.gltf_node = int(i);
        path.model = scene.cameras[scene.nodes[i].camera];
        return path;
    }
    Pose pose;
    evaluate_pose(scene, 0.0, pose);
    Bounds b = scene_bounds(scene, pose);
    glm::vec3 center = b.empty ? glm::vec3(0.0f) : 0.5f * (b.min + b.max);
    float radius = b.empty ? 1.0f : std::max(0.5f * glm::length(b.max - b.min), 1e-3f);
    path.motion = CameraMotion::Orbit;
    path.target = center;
    float distance = radius / std::sin(0.5f * path.model.yfov) * 1.1f;
    path.eye = center + glm::vec3(0.0f, 0.35f, 0.94f) * distance;
    path.model.znear = std::max(distance - radius, distance * 1e-3f) * 0.5f;
    path.model.zfar = (distance + radius) * 2.0f;
    path.speed = 0.4f;
    return path;
}

Status parse_camera_spec(const std::string& spec, const Scene& scene, const CameraPath& fallback,
                         CameraPath& path) {
    path = fallback;
    std::string kind = spec.substr(0, spec.find(':'));
    std::string params = kind.size() < spec.size() ? spec.substr(kind.size() + 1) : "";
    auto bad = [&](const std::string& why) {
        return Status::error("camera '" + spec + "': " + why);
    };
    static const std::pair<const char*, CameraMotion> kinds[] = {
        {"static", CameraMotion::Static}, {"orbit", CameraMotion::Orbit},
        {"pan", CameraMotion::Pan},       {"dolly", CameraMotion::Dolly},
        {"shake", CameraMotion::Shake},   {"cut", CameraMotion::Cut},
        {"gltf", CameraMotion::Gltf}};
    bool known = false;
    for (auto& [name, motion] : kinds)
        if (kind == name) path.motion = motion, known = true;
    if (!known && kind.find(',') != std::string::npos)
        return bad("parameters follow a colon: " + kind.substr(0, kind.find(',')) + ":" +
                   kind.substr(kind.find(',') + 1));
    if (!known) return bad("unknown path (static, orbit, pan, dolly, shake, cut, gltf)");
    if (path.motion == CameraMotion::Dolly && fallback.motion != CameraMotion::Dolly)
        path.direction = glm::normalize(fallback.target - fallback.eye);
    if (path.motion == CameraMotion::Gltf) {
        int wanted = 0, seen = 0;
        if (!params.empty()) {
            auto [end, ec] = std::from_chars(params.data(), params.data() + params.size(), wanted);
            if (ec != std::errc() || end != params.data() + params.size() || wanted < 0)
                return bad("expected gltf or gltf:N with N a camera number");
        }
        for (std::size_t i = 0; i < scene.nodes.size(); ++i) {
            if (scene.nodes[i].camera < 0 || seen++ != wanted) continue;
            path.gltf_node = int(i);
            path.model = scene.cameras[scene.nodes[i].camera];
            return {};
        }
        return bad("the scene has " + std::to_string(seen) + " camera node(s)");
    }
    std::size_t start = 0;
    while (start < params.size()) {
        std::size_t end = params.find(',', start);
        if (end == std::string::npos) end = params.size();
        std::string item = params.substr(start, end - start);
        start = end + 1;
        auto eq = item.find('=');
        if (eq == std::string::npos) return bad("'" + item + "' is not key=value");
        std::string key = item.substr(0, eq), text = item.substr(eq + 1);
        float value = 0;
        auto [last, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
        if (ec != std::errc() || last != text.data() + text.size() || !std::isfinite(value))
            return bad("'" + text + "' is not a number");
        glm::vec3 offset = path.eye - path.target;
        if (key == "speed")
            path.speed = value;
        else if (key == "shake")
            path.shake = value;
        else if (key == "time")
            path.cut_time = value;
        else if (key == "angle")
            path.cut_angle = value;
        else if (key == "height")
            path.eye.y = path.target.y + value;
        else if (key == "radius") {
            float r = std::hypot(offset.x, offset.z);
            if (value <= 0) return bad("radius must be positive");
            glm::vec3 flat = r > 0 ? glm::vec3(offset.x, 0, offset.z) / r : glm::vec3(0, 0, 1);
            path.eye = path.target + flat * value + glm::vec3(0, offset.y, 0);
        } else
            return bad("unknown parameter '" + key +
                       "' (speed, radius, height, shake, time, angle)");
    }
    return {};
}

}  // namespace reprise::server
