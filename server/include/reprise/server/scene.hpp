#pragma once
// A renderable scene: the part of glTF 2.0 that reprise draws, also built in code for the
// built-in scenes. Everything here has been validated: indices are in range, values finite.
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace reprise::server {

struct Texture {
    int width = 0;
    int height = 0;
    std::vector<glm::u8vec4> pixels;  // RGBA8, sRGB-encoded colour, rows top to bottom
    bool repeat = true;               // false: clamp to edge
    bool nearest = false;             // magnification filter
};

struct Material {
    glm::vec4 base_color{1.0f};   // linear RGBA factor
    int base_color_texture = -1;  // index into Scene::textures
    int texcoord = 0;             // which UV set the texture uses (0 or 1)
    float specular = 0.25f;       // strength of the view-dependent highlight
    float shininess = 48.0f;      // Blinn-Phong exponent
    float mirror = 0.0f;          // 0..1: share of a procedural environment reflected (Lit)
    bool double_sided = false;
};

struct MorphTarget {
    std::vector<glm::vec3> positions;  // deltas, empty or one per vertex
    std::vector<glm::vec3> normals;
};

struct Primitive {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;    // empty: computed flat by the renderer
    std::vector<glm::vec2> uv0, uv1;   // empty or one per vertex
    std::vector<glm::u16vec4> joints;  // skinning, empty or one per vertex
    std::vector<glm::vec4> weights;
    std::vector<MorphTarget> targets;
    std::vector<uint32_t> indices;  // triangle list, each < positions.size()
    int material = -1;              // -1: default material
};

struct Mesh {
    std::string name;
    std::vector<Primitive> primitives;
    std::vector<float> weights;  // default morph weights, one per target
};

struct Skin {
    std::vector<int> joints;              // node indices
    std::vector<glm::mat4> inverse_bind;  // one per joint
};

struct Node {
    std::string name;
    std::vector<int> children;
    glm::vec3 translation{0.0f};
    glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  // w, x, y, z
    glm::vec3 scale{1.0f};
    glm::mat4 matrix{1.0f};  // used instead of TRS when has_matrix
    bool has_matrix = false;
    int mesh = -1;
    int skin = -1;
    int camera = -1;
    std::vector<float> weights;  // morph weights overriding the mesh's
    uint32_t object_id = 0;      // written to the id buffer; 0 = the renderer numbers it
};

enum class Interpolation { Linear, Step, CubicSpline };
enum class AnimatedPath { Translation, Rotation, Scale, Weights };

struct AnimationChannel {
    int node = -1;
    AnimatedPath path = AnimatedPath::Translation;
    Interpolation interpolation = Interpolation::Linear;
    std::vector<float> times;  // strictly increasing, finite
    // Keyframe values, flattened: per key `components` floats (3 T/S, 4 rotation xyzw,
    // number of morph targets for weights); CubicSpline stores in-tangent, value, out-tangent.
    std::vector<float> values;
    int components = 3;
};

struct Animation {
    std::string name;
    std::vector<AnimationChannel> channels;
};

struct CameraModel {
    bool perspective = true;
    float yfov = 0.8f;               // radians, perspective
    float aspect = 0.0f;             // 0: from the image size
    float xmag = 1.0f, ymag = 1.0f;  // orthographic half extents
    float znear = 0.1f;
    float zfar = 1000.0f;  // perspective may use an infinite far plane (0)
};

struct Light {
    glm::vec3 direction{-0.4f, -1.0f, -0.3f};  // travel direction of the light, world space
    glm::vec3 color{2.5f, 2.4f, 2.2f};
    glm::vec3 ambient{0.25f, 0.27f, 0.32f};
    float orbit = 0.0f;  // radians per second the direction turns about +Y (a moving sun)
};

// The light's travel direction at `time` seconds.
glm::vec3 light_direction_at(const Light& light, double time);

// A point light of the heavy shading mode (no shadow; quadratic falloff).
struct PointLight {
    glm::vec3 position{0.0f};
    glm::vec3 color{1.0f};
};

struct Scene {
    std::string name;
    std::vector<Node> nodes;
    std::vector<int> roots;  // nodes drawn, with their descendants
    std::vector<Mesh> meshes;
    std::vector<Material> materials;
    std::vector<Texture> textures;
    std::vector<Skin> skins;
    std::vector<Animation> animations;
    std::vector<CameraModel> cameras;
    Light light;
    std::vector<PointLight> point_lights;  // used by Shading::Heavy only (at most 16)
    bool heavy_shading = false;            // built for Shading::Heavy (the CLI's default for it)
    bool hud = false;  // the renderer draws the built-in HUD (draw_hud) into Frame::ui
    glm::vec3 background{0.55f, 0.70f, 0.90f};  // linear RGB of the sky (id 0)
    // Unique to each scene made (copies share it), never reused: how a renderer knows the
    // textures and caches it holds are this scene's (an address can belong to another scene
    // later). A scene's textures are not changed once it is built.
    std::uint64_t revision = next_scene_revision();

private:
    static std::uint64_t next_scene_revision() {
        static std::atomic<std::uint64_t> next{1};
        return next.fetch_add(1, std::memory_order_relaxed);
    }
};

}  // namespace reprise::server
