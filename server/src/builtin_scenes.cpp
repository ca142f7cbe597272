#include "reprise/server/builtin_scenes.hpp"

#include <cmath>
#include <filesystem>
#include <functional>

#include <glm/gtc/constants.hpp>

#include "reprise/server/gltf.hpp"

namespace reprise::server {

const std::vector<SceneInfo>& builtin_scenes() {
    static const std::vector<SceneInfo> scenes = {
        {"pan", "textured ground and boxes under a sideways camera pan (the default)"},
        {"fence", "thin poles and rails of a fence under an orbiting camera"},
        {"crossing", "objects crossing in front of each other and of a textured wall"},
        {"specular", "view-dependent highlights on shiny objects under an orbit"},
        {"fast", "a camera pan and an object moving over 100 px/frame at 1080p, 30 Hz"},
        {"cut", "an orbit with a hard camera cut at 0.5 s"},
        {"courtyard", "heavy shading: still camera, objects moving through soft shadows, 8 lights"},
        {"stroll", "heavy shading: a camera orbiting a plaza of marbled objects, 8 lights"},
        {"shadows", "heavy shading: a moving sun sweeps shadows over a still ground, still camera"},
        {"mirror",
         "a spinning mirror ball under an orbit: its reflections move unlike its surface"},
        {"hud", "a camera pan under a UI layer (ui.* channels): a static panel, a changing bar"},
    };
    return scenes;
}

namespace {

// ---- geometry ---------------------------------------------------------------------------

void add_quad(Primitive& p, glm::vec3 origin, glm::vec3 u, glm::vec3 v, glm::vec2 uv_scale) {
    uint32_t base = uint32_t(p.positions.size());
    glm::vec3 n = glm::normalize(glm::cross(u, v));
    const glm::vec2 corners[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (glm::vec2 c : corners) {
        p.positions.push_back(origin + c.x * u + c.y * v);
        p.normals.push_back(n);
        p.uv0.push_back(c * uv_scale);
    }
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) p.indices.push_back(base + i);
}

// Axis-aligned box centred on the origin; texture repeats once per `texel_size` units.
Primitive box(glm::vec3 size, float texel_size = 1.0f) {
    Primitive p;
    glm::vec3 h = 0.5f * size;
    auto uv = [&](float a, float b) { return glm::vec2(a, b) / texel_size; };
    add_quad(p, {-h.x, -h.y, h.z}, {size.x, 0, 0}, {0, size.y, 0}, uv(size.x, size.y));   // +z
    add_quad(p, {h.x, -h.y, -h.z}, {-size.x, 0, 0}, {0, size.y, 0}, uv(size.x, size.y));  // -z
    add_quad(p, {h.x, -h.y, h.z}, {0, 0, -size.z}, {0, size.y, 0}, uv(size.z, size.y));   // +x
    add_quad(p, {-h.x, -h.y, -h.z}, {0, 0, size.z}, {0, size.y, 0}, uv(size.z, size.y));  // -x
    add_quad(p, {-h.x, h.y, h.z}, {size.x, 0, 0}, {0, 0, -size.z}, uv(size.x, size.z));   // +y
    add_quad(p, {-h.x, -h.y, -h.z}, {size.x, 0, 0}, {0, 0, size.z}, uv(size.x, size.z));  // -y
    return p;
}

// Horizontal plane at y = 0 centred on the origin.
Primitive ground(float width, float depth, float texel_size) {
    Primitive p;
    add_quad(p, {-0.5f * width, 0, 0.5f * depth}, {width, 0, 0}, {0, 0, -depth},
             glm::vec2(width, depth) / texel_size);
    return p;
}

// Vertical plane facing +z, bottom edge centred on the origin.
Primitive wall(float width, float height, float texel_size) {
    Primitive p;
    add_quad(p, {-0.5f * width, 0, 0}, {width, 0, 0}, {0, height, 0},
             glm::vec2(width, height) / texel_size);
    return p;
}

Primitive cylinder(float radius, float height, int segments) {
    Primitive p;
    for (int i = 0; i <= segments; ++i) {
        float a = glm::two_pi<float>() * float(i) / float(segments);
        glm::vec3 n(std::cos(a), 0, std::sin(a));
        for (float y : {0.0f, height}) {
            p.positions.push_back(radius * n + glm::vec3(0, y, 0));
            p.normals.push_back(n);
            p.uv0.push_back({float(i) / float(segments), y});
        }
    }
    for (int i = 0; i < segments; ++i) {
        uint32_t a = uint32_t(2 * i);
        for (uint32_t k : {a, a + 1, a + 2, a + 2, a + 1, a + 3}) p.indices.push_back(k);
    }
    uint32_t top = uint32_t(p.positions.size());
    p.positions.push_back({0, height, 0});
    p.normals.push_back({0, 1, 0});
    p.uv0.push_back({0.5f, 0.5f});
    for (int i = 0; i <= segments; ++i) {
        float a = glm::two_pi<float>() * float(i) / float(segments);
        p.positions.push_back({radius * std::cos(a), height, radius * std::sin(a)});
        p.normals.push_back({0, 1, 0});
        p.uv0.push_back({0.5f + 0.5f * std::cos(a), 0.5f + 0.5f * std::sin(a)});
    }
    for (int i = 0; i < segments; ++i)
        for (uint32_t k : {top, top + 2 + uint32_t(i), top + 1 + uint32_t(i)})
            p.indices.push_back(k);
    return p;
}

Primitive sphere(float radius, int rings, int segments) {
    Primitive p;
    for (int r = 0; r <= rings; ++r) {
        float phi = glm::pi<float>() * float(r) / float(rings);
        for (int s = 0; s <= segments; ++s) {
            float theta = glm::two_pi<float>() * float(s) / float(segments);
            glm::vec3 n(std::sin(phi) * std::cos(theta), std::cos(phi),
                        std::sin(phi) * std::sin(theta));
            p.positions.push_back(radius * n);
            p.normals.push_back(n);
            p.uv0.push_back({2.0f * float(s) / float(segments), float(r) / float(rings)});
        }
    }
    uint32_t row = uint32_t(segments + 1);
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            uint32_t a = uint32_t(r) * row + uint32_t(s), b = a + row;
            for (uint32_t k : {a, a + 1, b, b, a + 1, b + 1}) p.indices.push_back(k);
        }
    return p;
}

// ---- textures ---------------------------------------------------------------------------

float smooth_noise(float x, float y, uint32_t seed) {
    auto hash = [seed](int i, int j) {
        uint32_t h = uint32_t(i) * 73856093u ^ uint32_t(j) * 19349663u ^ seed * 83492791u;
        h ^= h >> 13;
        h *= 0x5bd1e995u;
        h ^= h >> 15;
        return float(h & 0xffff) / 65535.0f;
    };
    int i = int(std::floor(x)), j = int(std::floor(y));
    float fx = x - float(i), fy = y - float(j);
    fx = fx * fx * (3 - 2 * fx);
    fy = fy * fy * (3 - 2 * fy);
    float a = hash(i, j), b = hash(i + 1, j), c = hash(i, j + 1), d = hash(i + 1, j + 1);
    return (a + (b - a) * fx) * (1 - fy) + (c + (d - c) * fx) * fy;
}

// A tileable 256x256 texture from a function of (u, v) in [0, 1) returning display RGB.
Texture make_texture(const std::function<glm::vec3(float, float)>& shade) {
    Texture t;
    t.width = t.height = 256;
    t.pixels.resize(256 * 256);
    for (int y = 0; y < 256; ++y)
        for (int x = 0; x < 256; ++x) {
            glm::vec3 c = glm::clamp(shade((x + 0.5f) / 256.0f, (y + 0.5f) / 256.0f), 0.0f, 1.0f);
            t.pixels[y * 256 + x] = glm::u8vec4(glm::round(c * 255.0f), 255);
        }
    return t;
}

// Soft-edged tiles with a slowly varying tint: detail a warp must carry, without aliasing.
Texture tiles_texture(glm::vec3 a, glm::vec3 b, uint32_t seed) {
    return make_texture([=](float u, float v) {
        auto soft = [](float x) {  // square wave with ramps 1/16 of a tile wide
            float f = x - std::floor(x);
            float rise = glm::smoothstep(0.0f, 0.0625f, f) - glm::smoothstep(0.5f, 0.5625f, f);
            return rise;
        };
        float checker = soft(4 * u) * soft(4 * v) + (1 - soft(4 * u)) * (1 - soft(4 * v));
        float tint = 0.75f + 0.25f * smooth_noise(16 * u, 16 * v, seed);
        // Noise must tile: fade to its value at the wrap.
        return glm::mix(b, a, checker) * tint;
    });
}

Texture noise_texture(glm::vec3 a, glm::vec3 b, uint32_t seed) {
    return make_texture([=](float u, float v) {
        float n =
            0.6f * smooth_noise(8 * u, 8 * v, seed) + 0.4f * smooth_noise(24 * u, 24 * v, seed + 7);
        float stripes = 0.5f + 0.5f * std::sin(glm::two_pi<float>() * 6 * (u + 0.1f * n));
        return glm::mix(a, b, 0.6f * n + 0.4f * stripes);
    });
}

// ---- scene assembly ---------------------------------------------------------------------

struct Builder {
    Scene scene;

    int texture(Texture t) {
        scene.textures.push_back(std::move(t));
        return int(scene.textures.size()) - 1;
    }
    int material(glm::vec3 color, int tex = -1, float specular = 0.15f, float shininess = 32.0f) {
        scene.materials.push_back({.base_color = glm::vec4(color, 1.0f),
                                   .base_color_texture = tex,
                                   .specular = specular,
                                   .shininess = shininess});
        return int(scene.materials.size()) - 1;
    }
    int add(std::string name, Primitive p, int mat, glm::vec3 at,
            glm::quat rotation = glm::quat(1, 0, 0, 0)) {
        p.material = mat;
        scene.meshes.push_back({.name = name, .primitives = {std::move(p)}});
        Node n;
        n.name = std::move(name);
        n.mesh = int(scene.meshes.size()) - 1;
        n.translation = at;
        n.rotation = rotation;
        scene.nodes.push_back(std::move(n));
        scene.roots.push_back(int(scene.nodes.size()) - 1);
        return int(scene.nodes.size()) - 1;
    }
    // Constant velocity, through the node's position at t = 0, from t = -1 s to `seconds` (two
    // linear keys: exact at every instant, including the instant before frame 0).
    void move(int node, glm::vec3 velocity, float seconds = 60.0f) {
        glm::vec3 a = scene.nodes[node].translation - velocity, b = a + velocity * (seconds + 1.0f);
        channel(node, AnimatedPath::Translation, {-1.0f, seconds}, {a.x, a.y, a.z, b.x, b.y, b.z},
                3);
    }
    // Constant spin about an axis, keyed every quarter turn.
    void spin(int node, glm::vec3 axis, float radians_per_second, float seconds = 60.0f) {
        std::vector<float> times, values;
        float step = glm::half_pi<float>() / std::abs(radians_per_second);
        for (float t = -step; t <= seconds + step; t += step) {
            glm::quat q = glm::angleAxis(radians_per_second * t, glm::normalize(axis));
            times.push_back(t);
            values.insert(values.end(), {q.x, q.y, q.z, q.w});
        }
        channel(node, AnimatedPath::Rotation, times, values, 4);
    }
    void channel(int node, AnimatedPath path, std::vector<float> times, std::vector<float> values,
                 int components) {
        if (scene.animations.empty()) scene.animations.push_back({.name = "builtin"});
        scene.animations[0].channels.push_back({.node = node,
                                                .path = path,
                                                .interpolation = Interpolation::Linear,
                                                .times = std::move(times),
                                                .values = std::move(values),
                                                .components = components});
    }
};

CameraModel builtin_lens() {
    return {.perspective = true, .yfov = glm::radians(50.0f), .znear = 0.1f, .zfar = 500.0f};
}

void add_boxes(Builder& b, int material, float x0, float x1, float z0, float z1, int count,
               uint32_t seed) {
    for (int i = 0; i < count; ++i) {
        float r1 = smooth_noise(i * 1.7f + 0.3f, 0.5f, seed),
              r2 = smooth_noise(0.5f, i * 2.3f + 0.7f, seed);
        float r3 = smooth_noise(i * 3.1f + 0.1f, i * 0.9f, seed + 1);
        glm::vec3 size(0.8f + 1.6f * r1, 0.8f + 2.2f * r2, 0.8f + 1.2f * r3);
        float x = x0 + (x1 - x0) * (float(i) + 0.5f) / float(count);
        float z = z0 + (z1 - z0) * r3;
        glm::quat turn = glm::angleAxis(0.6f * (r1 - 0.5f), glm::vec3(0, 1, 0));
        b.add("box" + std::to_string(i), box(size), material, {x, 0.5f * size.y, z}, turn);
    }
}

Scene pan_scene(CameraPath& camera, float speed) {
    Builder b;
    b.scene.name = speed > 10 ? "fast" : "pan";
    int grass = b.material({1, 1, 1},
                           b.texture(tiles_texture({0.55f, 0.5f, 0.4f}, {0.3f, 0.42f, 0.25f}, 3)));
    int crate = b.material({1, 1, 1},
                           b.texture(noise_texture({0.6f, 0.35f, 0.2f}, {0.9f, 0.75f, 0.5f}, 5)));
    float length = speed > 10 ? 400.0f : 80.0f;
    b.add("ground", ground(length, 60, 4), grass, {0.5f * length - 20, 0, 0});
    add_boxes(b, crate, -10, length - 30, -9, -3, speed > 10 ? 60 : 14, 11);
    if (speed > 10) {  // something overtaking the camera
        int ball = b.add("ball", sphere(0.6f, 24, 48), crate, {-8, 0.6f, -1});
        b.move(ball, {1.6f * speed, 0, 0});
        b.spin(ball, {0, 0, 1}, -1.6f * speed / 0.6f);
    }
    camera = {.motion = CameraMotion::Pan,
              .target = {-4, 1.0f, -6},
              .eye = {-4, 2.2f, 4},
              .speed = speed,
              .direction = {1, 0, 0},
              .model = builtin_lens()};
    return std::move(b.scene);
}

Scene fence_scene(CameraPath& camera) {
    Builder b;
    b.scene.name = "fence";
    int grass = b.material({1, 1, 1},
                           b.texture(tiles_texture({0.5f, 0.55f, 0.35f}, {0.35f, 0.45f, 0.3f}, 9)));
    int wood = b.material({0.45f, 0.3f, 0.18f});
    int paint = b.material({1, 1, 1},
                           b.texture(noise_texture({0.7f, 0.2f, 0.15f}, {0.95f, 0.9f, 0.8f}, 4)));
    b.add("ground", ground(60, 60, 4), grass, {0, 0, 0});
    for (int i = 0; i <= 24; ++i)
        b.add("pole" + std::to_string(i), cylinder(0.035f, 1.4f, 12), wood, {-6 + 0.5f * i, 0, 0});
    for (float y : {0.45f, 1.05f}) b.add("rail", box({12.2f, 0.05f, 0.03f}), wood, {0, y, 0.05f});
    b.add("house", box({5, 3, 3}, 1.5f), paint, {1, 1.5f, -4});
    b.add("shed", box({2, 2, 2}, 1.5f), paint, {-3.5f, 1.0f, -2.5f});
    camera = {.motion = CameraMotion::Orbit,
              .target = {0, 0.8f, -1},
              .eye = {0, 1.8f, 6},
              .speed = 0.25f,
              .model = builtin_lens()};
    return std::move(b.scene);
}

Scene crossing_scene(CameraPath& camera) {
    Builder b;
    b.scene.name = "crossing";
    int floor = b.material({1, 1, 1},
                           b.texture(tiles_texture({0.6f, 0.6f, 0.55f}, {0.35f, 0.35f, 0.4f}, 2)));
    int poster =
        b.material({1, 1, 1}, b.texture(noise_texture({0.15f, 0.3f, 0.6f}, {0.9f, 0.8f, 0.4f}, 8)));
    int red = b.material({1, 1, 1},
                         b.texture(tiles_texture({0.8f, 0.15f, 0.1f}, {0.95f, 0.85f, 0.8f}, 6)));
    int green =
        b.material({1, 1, 1}, b.texture(noise_texture({0.1f, 0.5f, 0.2f}, {0.8f, 0.9f, 0.6f}, 12)));
    b.add("floor", ground(40, 30, 3), floor, {0, 0, 0});
    b.add("wall", wall(30, 10, 3), poster, {0, 0, -6});
    int cube = b.add("cube", box({1.2f, 1.2f, 1.2f}, 0.6f), red, {-5, 0.6f, -1});
    b.move(cube, {2.5f, 0, 0});
    b.spin(cube, {0, 1, 0}, 1.2f);
    int ball = b.add("ball", sphere(0.8f, 24, 48), green, {5, 0.8f, -3});
    b.move(ball, {-2.0f, 0, 0});
    b.spin(ball, {0, 0, 1}, 2.0f / 0.8f);
    int post = b.add("post", cylinder(0.3f, 2.2f, 24), red, {-6, 0, 1});
    b.move(post, {4.0f, 0, 0});
    camera = {.motion = CameraMotion::Static,
              .target = {0, 1.0f, -2},
              .eye = {0, 2.0f, 7},
              .model = builtin_lens()};
    return std::move(b.scene);
}

Scene specular_scene(CameraPath& camera) {
    Builder b;
    b.scene.name = "specular";
    b.scene.light.direction = {-0.6f, -0.5f, -0.6f};
    int floor = b.material({1, 1, 1},
                           b.texture(tiles_texture({0.3f, 0.3f, 0.32f}, {0.5f, 0.48f, 0.45f}, 1)),
                           0.6f, 80.0f);
    int chrome = b.material({0.6f, 0.6f, 0.65f}, -1, 1.5f, 120.0f);
    int gold = b.material({0.8f, 0.55f, 0.2f}, -1, 1.2f, 60.0f);
    int plastic =
        b.material({1, 1, 1}, b.texture(noise_texture({0.1f, 0.2f, 0.7f}, {0.7f, 0.8f, 0.95f}, 3)),
                   0.9f, 200.0f);
    b.add("floor", ground(40, 40, 2), floor, {0, 0, 0});
    b.add("chrome ball", sphere(1.0f, 32, 64), chrome, {-1.8f, 1.0f, 0});
    b.add("gold box", box({1.4f, 1.4f, 1.4f}), gold, {1.6f, 0.7f, -0.5f},
          glm::angleAxis(0.5f, glm::vec3(0, 1, 0)));
    int spinner = b.add("spinner", sphere(0.7f, 32, 64), plastic, {0.2f, 0.7f, 1.8f});
    b.spin(spinner, {0, 1, 0}, 0.8f);
    camera = {.motion = CameraMotion::Orbit,
              .target = {0, 0.8f, 0},
              .eye = {0, 2.5f, 6.5f},
              .speed = 0.3f,
              .model = builtin_lens()};
    return std::move(b.scene);
}

Scene cut_scene(CameraPath& camera) {
    Scene scene = fence_scene(camera);
    scene.name = "cut";
    camera.motion = CameraMotion::Cut;
    camera.cut_time = 0.5f;
    camera.cut_angle = 2.2f;
    return scene;
}

// Eight coloured point lights on a ring `radius` around `centre`, `height` above the ground.
void ring_of_lights(Scene& scene, glm::vec3 centre, float radius, float height, float power) {
    const glm::vec3 tints[4] = {
        {1.0f, 0.75f, 0.5f}, {0.55f, 0.7f, 1.0f}, {1.0f, 0.55f, 0.7f}, {0.6f, 1.0f, 0.7f}};
    for (int i = 0; i < 8; ++i) {
        float a = glm::two_pi<float>() * (float(i) + 0.5f) / 8.0f;
        scene.point_lights.push_back(
            {.position = centre + glm::vec3(radius * std::cos(a), height, radius * std::sin(a)),
             .color = power * tints[i % 4]});
    }
}

Scene courtyard_scene(CameraPath& camera) {
    Builder b;
    b.scene.name = "courtyard";
    b.scene.heavy_shading = true;
    b.scene.light = {.direction = {-0.5f, -1.0f, -0.35f},
                     .color = {1.0f, 0.95f, 0.85f},
                     .ambient = {0.1f, 0.11f, 0.14f}};
    int stone = b.material({0.85f, 0.82f, 0.78f}, -1, 0.2f, 24.0f);
    int brick = b.material({0.8f, 0.5f, 0.4f}, -1, 0.1f, 16.0f);
    int marble = b.material({0.9f, 0.9f, 0.95f}, -1, 0.6f, 64.0f);
    int bronze = b.material({0.75f, 0.55f, 0.3f}, -1, 0.8f, 48.0f);
    b.add("ground", ground(30, 24, 4), stone, {0, 0, -2});
    b.add("wall", wall(30, 8, 3), brick, {0, 0, -8});
    for (int i = 0; i < 4; ++i)
        b.add("pillar" + std::to_string(i), cylinder(0.35f, 4.0f, 24), marble,
              {-4.5f + 3.0f * i, 0, -5.5f});
    int cube = b.add("cube", box({1.2f, 1.2f, 1.2f}, 0.6f), bronze, {-4, 0.6f, -1});
    b.move(cube, {1.6f, 0, 0});
    b.spin(cube, {0, 1, 0}, 0.9f);
    int ball = b.add("ball", sphere(0.7f, 24, 48), marble, {4, 0.7f, -3});
    b.move(ball, {-1.4f, 0, 0});
    b.spin(ball, {0, 0, 1}, 1.4f / 0.7f);
    int slab = b.add("slab", box({0.4f, 2.4f, 1.6f}, 0.8f), brick, {1.5f, 1.2f, 0.5f});
    b.spin(slab, {0, 1, 0}, 0.6f);
    ring_of_lights(b.scene, {0, 0, -2.5f}, 5.0f, 2.2f, 1.5f);
    camera = {.motion = CameraMotion::Static,
              .target = {0, 1.0f, -3},
              .eye = {0, 3.0f, 6},
              .model = builtin_lens()};
    return std::move(b.scene);
}

Scene stroll_scene(CameraPath& camera) {
    Builder b;
    b.scene.name = "stroll";
    b.scene.heavy_shading = true;
    b.scene.light = {.direction = {-0.6f, -0.9f, -0.4f},
                     .color = {1.0f, 0.95f, 0.85f},
                     .ambient = {0.1f, 0.11f, 0.14f}};
    int stone = b.material({0.8f, 0.78f, 0.72f}, -1, 0.2f, 24.0f);
    int marble = b.material({0.92f, 0.9f, 0.88f}, -1, 0.7f, 80.0f);
    int moss = b.material({0.45f, 0.6f, 0.35f}, -1, 0.05f, 8.0f);
    int bronze = b.material({0.75f, 0.55f, 0.3f}, -1, 0.8f, 48.0f);
    b.add("ground", ground(40, 40, 4), stone, {0, 0, 0});
    for (int i = 0; i < 6; ++i) {
        float a = glm::two_pi<float>() * float(i) / 6.0f;
        glm::vec3 at(3.5f * std::cos(a), 0, 3.5f * std::sin(a));
        b.add("column" + std::to_string(i), cylinder(0.3f, 2.5f + 0.4f * float(i % 3), 24), marble,
              at);
    }
    b.add("plinth", box({2.0f, 0.8f, 2.0f}, 1.0f), moss, {0, 0.4f, 0});
    b.add("statue", sphere(0.7f, 24, 48), bronze, {0, 1.5f, 0});
    b.add("bench", box({2.5f, 0.5f, 0.7f}, 1.0f), moss, {-1.5f, 0.25f, 5.5f},
          glm::angleAxis(0.3f, glm::vec3(0, 1, 0)));
    ring_of_lights(b.scene, {0, 0, 0}, 6.0f, 2.5f, 2.0f);
    camera = {.motion = CameraMotion::Orbit,
              .target = {0, 1.0f, 0},
              .eye = {0, 3.0f, 8.5f},
              .speed = 0.25f,
              .model = builtin_lens()};
    return std::move(b.scene);
}

// The shadows move, nothing else does: rendered motion is zero everywhere.
Scene shadows_scene(CameraPath& camera) {
    Builder b;
    b.scene.name = "shadows";
    b.scene.heavy_shading = true;
    b.scene.light = {.direction = {-0.8f, -0.55f, -0.3f},
                     .color = {1.3f, 1.22f, 1.08f},
                     .ambient = {0.16f, 0.18f, 0.24f},
                     .orbit = 0.8f};
    int stone = b.material({0.85f, 0.82f, 0.78f}, -1, 0.1f, 16.0f);
    int marble = b.material({0.9f, 0.88f, 0.86f}, -1, 0.3f, 32.0f);
    int brick = b.material({0.8f, 0.5f, 0.4f}, -1, 0.1f, 16.0f);
    b.add("ground", ground(16, 12, 4), stone, {0, 0, -1});
    for (int i = 0; i < 3; ++i)
        b.add("pillar" + std::to_string(i), cylinder(0.25f, 2.6f, 24), marble,
              {-3.0f + 3.0f * float(i), 0, -3.0f + 0.8f * float(i % 2)});
    b.add("block", box({1.0f, 1.4f, 1.0f}, 0.7f), brick, {1.6f, 0.7f, 0.6f},
          glm::angleAxis(0.4f, glm::vec3(0, 1, 0)));
    b.add("ball", sphere(0.5f, 24, 48), marble, {-1.8f, 0.5f, 0.8f});
    camera = {.motion = CameraMotion::Static,
              .target = {0, 0.3f, -1.5f},
              .eye = {0, 5.5f, 6.5f},
              .model = builtin_lens()};
    return std::move(b.scene);
}

Scene mirror_scene(CameraPath& camera) {
    Builder b;
    b.scene.name = "mirror";
    b.scene.light.direction = {-0.5f, -0.8f, -0.4f};
    int floor = b.material({1, 1, 1},
                           b.texture(tiles_texture({0.6f, 0.58f, 0.5f}, {0.35f, 0.38f, 0.42f}, 5)));
    int crate = b.material({1, 1, 1},
                           b.texture(noise_texture({0.6f, 0.35f, 0.2f}, {0.9f, 0.75f, 0.5f}, 6)));
    Material chrome{.base_color = glm::vec4(0.8f, 0.8f, 0.85f, 1.0f),
                    .specular = 1.0f,
                    .shininess = 200.0f,
                    .mirror = 0.9f};
    b.scene.materials.push_back(chrome);
    const int mirror = int(b.scene.materials.size()) - 1;
    b.add("floor", ground(40, 40, 2), floor, {0, 0, 0});
    // Spinning: its surface moves, what it reflects hardly does.
    const int ball = b.add("mirror ball", sphere(1.3f, 48, 96), mirror, {0, 1.3f, 0});
    b.spin(ball, {0, 1, 0}, 1.5f);
    b.add("crate", box({1.0f, 1.0f, 1.0f}), crate, {2.6f, 0.5f, -1.2f},
          glm::angleAxis(0.3f, glm::vec3(0, 1, 0)));
    camera = {.motion = CameraMotion::Orbit,
              .target = {0, 1.1f, 0},
              .eye = {0, 2.0f, 5.0f},
              .speed = 0.5f,
              .model = builtin_lens()};
    return std::move(b.scene);
}

}  // namespace

Status load_scene(const std::string& name_or_file, Scene& scene, CameraPath& camera,
                  const GltfOptions& gltf) {
    const std::string& n = name_or_file;
    if (n == "pan")
        scene = pan_scene(camera, 1.5f);
    else if (n == "fast")
        scene = pan_scene(camera, 24.0f);
    else if (n == "fence")
        scene = fence_scene(camera);
    else if (n == "crossing")
        scene = crossing_scene(camera);
    else if (n == "specular")
        scene = specular_scene(camera);
    else if (n == "cut")
        scene = cut_scene(camera);
    else if (n == "courtyard")
        scene = courtyard_scene(camera);
    else if (n == "stroll")
        scene = stroll_scene(camera);
    else if (n == "shadows")
        scene = shadows_scene(camera);
    else if (n == "mirror")
        scene = mirror_scene(camera);
    else if (n == "hud") {
        scene = pan_scene(camera, 3.0f);
        scene.name = "hud";
        scene.hud = true;
    } else {
        auto ext = std::filesystem::path(n).extension().string();
        if (ext != ".gltf" && ext != ".glb")
            return Status::error("scene '" + n +
                                 "' is neither a built-in scene (see `reprise scenes`) nor a "
                                 ".gltf/.glb file");
        REPRISE_TRY(load_gltf(n, scene, gltf));
        camera = default_camera_path(scene);
    }
    return {};
}

}  // namespace reprise::server
