#include "reprise/server/renderer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <vector>

#include <GLES3/gl32.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "gbuffer_shaders.hpp"
#include "heavy_shaders.hpp"
#include "reprise/core/memory_limit.hpp"
#include "reprise/gl/context.hpp"
#include "reprise/gl/program.hpp"
#include "reprise/server/animation.hpp"
#include "reprise/server/builtin_scenes.hpp"

namespace reprise::server {

namespace {

constexpr float kNoPrevious = 1e29f;  // the shader writes 1e30 where there is no previous position

struct Vertex {
    glm::vec3 position;
    glm::vec3 previous;
    glm::vec3 normal;
    glm::vec2 uv;
};

struct Draw {
    GLsizei first_index;
    GLsizei index_count;
    int material;
    float id;
    bool mirrored;  // node transform with negative determinant flips the winding
};

constexpr int kShadowMapSize = 1024;

// Supersampling's sample positions in pixels from the pixel centre (+y down): Direct3D's standard
// 2x, 4x, 8x and 16x patterns (sixteenths of a pixel), distinct in x and in y.
constexpr glm::vec2 kSamples2[] = {{4, 4}, {-4, -4}};
constexpr glm::vec2 kSamples4[] = {{-2, -6}, {6, -2}, {-6, 2}, {2, 6}};
constexpr glm::vec2 kSamples8[] = {{1, -3}, {-1, 3},  {5, 1}, {-3, -5},
                                   {-5, 5}, {-7, -1}, {3, 7}, {7, -7}};
constexpr glm::vec2 kSamples16[] = {{1, 1},  {-1, -3}, {-3, 2}, {4, -1}, {-5, -2}, {2, 5},
                                    {5, 3},  {3, -5},  {-2, 6}, {0, -7}, {-4, -6}, {-6, 4},
                                    {-8, 0}, {7, -4},  {6, 7},  {-7, -8}};

const glm::vec2* supersample_positions(int samples) {
    switch (samples) {
        case 2:
            return kSamples2;
        case 4:
            return kSamples4;
        case 8:
            return kSamples8;
        case 16:
            return kSamples16;
    }
    return nullptr;
}

// The jittered view-projection: pixel p samples the unjittered image at p + offset.
glm::mat4 shifted(const glm::mat4& view_projection, glm::vec2 offset, int w, int h) {
    return glm::translate(glm::mat4(1.0f), glm::vec3(-2.0f * offset.x / float(w),
                                                     2.0f * offset.y / float(h), 0.0f)) *
           view_projection;
}

// CPU time of all threads of this process (llvmpipe shades on its own threads): on a shared
// machine it varies far less than wall time.
double process_cpu_ms() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

// Area-weighted vertex normals for primitives that come without them.
void smooth_normals(const std::vector<glm::vec3>& positions, const std::vector<uint32_t>& indices,
                    std::vector<glm::vec3>& normals) {
    normals.assign(positions.size(), glm::vec3(0.0f));
    for (std::size_t i = 0; i + 2 < indices.size(); i += 3) {
        uint32_t a = indices[i], b = indices[i + 1], c = indices[i + 2];
        glm::vec3 n = glm::cross(positions[b] - positions[a], positions[c] - positions[a]);
        normals[a] += n, normals[b] += n, normals[c] += n;
    }
}

Status check_heavy_settings(const RenderSettings& settings) {
    if (settings.heavy_octaves < 1 || settings.heavy_octaves > 16)
        return Status::error("heavy shading: octaves must be in 1..16");
    if (settings.heavy_pcf_radius < 0 || settings.heavy_pcf_radius > 8)
        return Status::error("heavy shading: PCF radius must be in 0..8");
    const ReuseSettings& r = settings.reuse;
    if (r.period < 1 || r.period > 255)
        return Status::error("reuse: refresh period " + std::to_string(r.period) +
                             " must be in 1..255");
    if (!(r.threshold > 0.0f && r.threshold <= 1.0f))
        return Status::error("reuse: threshold must be in (0, 1]");
    if (r.filter_radius < 0 || r.filter_radius > 3)
        return Status::error("reuse: filter radius must be in 0..3");
    if (!(r.depth_epsilon >= 0.0f && r.depth_epsilon <= 1e6f))
        return Status::error("reuse: depth epsilon must be in [0, 1e6] Z-buffer increments");
    if (!(r.smoothing >= 0.0f && r.smoothing <= 1.0f))
        return Status::error("reuse: smoothing alpha must be in [0, 1]");
    return {};
}

// Orthographic light view around the bounding sphere of everything drawn.
template <class Vertices>
glm::mat4 shadow_light_matrix(const Vertices& vertices, glm::vec3 direction) {
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (const auto& v : vertices) lo = glm::min(lo, v.position), hi = glm::max(hi, v.position);
    if (vertices.empty()) lo = hi = glm::vec3(0.0f);
    const glm::vec3 centre = 0.5f * (lo + hi);
    const float radius = std::max(0.5f * glm::length(hi - lo), 1e-3f);
    glm::vec3 d = glm::length(direction) > 0.0f ? glm::normalize(direction) : glm::vec3(0, -1, 0);
    glm::vec3 up = std::abs(d.y) > 0.99f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    glm::mat4 view = glm::lookAt(centre - 2.0f * radius * d, centre, up);
    return glm::ortho(-radius, radius, -radius, radius, radius, 3.0f * radius) * view;
}

}  // namespace

const char* to_string(Refresh refresh) {
    switch (refresh) {
        case Refresh::Tiled:
            return "tiled";
        case Refresh::Random:
            return "random";
        case Refresh::Blocks:
            return "blocks";
        case Refresh::Interleaved:
            return "interleaved";
    }
    return "?";
}

Status parse_refresh(const std::string& spec, ReuseSettings& reuse) {
    const std::size_t colon = spec.find(':');
    const std::string kind = spec.substr(0, colon);
    if (kind == "tiled")
        reuse.refresh = Refresh::Tiled;
    else if (kind == "random")
        reuse.refresh = Refresh::Random;
    else if (kind == "blocks")
        reuse.refresh = Refresh::Blocks;
    else if (kind == "interleaved")
        reuse.refresh = Refresh::Interleaved;
    else
        return Status::error("--refresh '" + spec +
                             "': the kind must be tiled, random, blocks or interleaved");
    if (colon != std::string::npos) {
        const std::string n = spec.substr(colon + 1);
        char* end = nullptr;
        long period = std::strtol(n.c_str(), &end, 10);
        if (n.empty() || *end != '\0' || period < 1 || period > 255)
            return Status::error("--refresh '" + spec +
                                 "': the period must be an integer in 1..255");
        reuse.period = int(period);
    }
    return {};
}

namespace {}  // namespace

struct Renderer::Gpu {
    std::unique_ptr<gl::Context> context;
    GLuint program = 0;
    GLuint active = 0;  // the program uniform() looks names up in
    // Heavy shading: its program, the key light's shadow map and the ping-pong reuse cache.
    // Full shading, the hit pass and the miss pass of reuse (heavy_shaders.hpp).
    GLuint heavy_program[3] = {}, shadow_program = 0;
    GLuint shadow_framebuffer = 0, shadow_map = 0;
    GLuint cache_term[2] = {}, cache_meta[2] = {};
    int cache_slot = 0;        // the slot written by the next reusing frame
    bool cache_valid = false;  // the other slot holds the frame rendered at cache_time/view
    double cache_time = 0.0;
    glm::mat4 cache_view{0.0f};
    std::uint64_t cache_scene = 0;  // its revision
    int reuse_frame = 0;
    ReuseStats stats;
    ReuseMaps maps;
    GLuint framebuffer = 0;
    GLuint targets[3] = {};  // colour, (depth, motion, id), normal
    GLuint depth_buffer = 0;
    // Anti-aliased colour by MSAA: a multisampled colour and depth target, resolved into
    // targets[0] after the single-sample G-buffer pass.
    GLuint msaa_framebuffer = 0, msaa_color = 0, msaa_depth = 0;
    int msaa_samples = 0, msaa_width = 0, msaa_height = 0;
    std::vector<GLint> msaa_counts;  // sample counts of RGBA32F renderbuffers on this device
    bool software = false;           // llvmpipe or softpipe
    GLuint vertex_array = 0, vertex_buffer = 0, index_buffer = 0;
    int width = 0, height = 0;
    int max_target_size = 0;  // GL_MAX_RENDERBUFFER_SIZE and GL_MAX_TEXTURE_SIZE, the smaller
    int cache_width = 0, cache_height = 0;
    float max_anisotropy = 0.0f;
    Frame lowres_scratch;  // the low-resolution render of render_frame_lowres
    // Textures of the scene last drawn, recognised by its revision and its texture storage.
    std::uint64_t scene_revision = 0;
    const void* scene_texture_data = nullptr;
    std::vector<GLuint> textures;
    // Per-frame scratch, kept between frames.
    Pose pose, previous_pose;
    std::vector<Vertex> vertices;
    std::vector<uint32_t> indices;
    std::vector<Draw> draws;
    std::vector<glm::vec3> positions, previous_positions, normals, unused;
    std::vector<glm::vec4> readback;

    ~Gpu() {
        if (!context) return;
        context->make_current();
        glDeleteTextures(GLsizei(textures.size()), textures.data());
        glDeleteTextures(3, targets);
        glDeleteRenderbuffers(1, &depth_buffer);
        glDeleteFramebuffers(1, &framebuffer);
        glDeleteFramebuffers(1, &msaa_framebuffer);
        glDeleteRenderbuffers(1, &msaa_color);
        glDeleteRenderbuffers(1, &msaa_depth);
        glDeleteBuffers(1, &vertex_buffer);
        glDeleteBuffers(1, &index_buffer);
        glDeleteVertexArrays(1, &vertex_array);
        glDeleteProgram(program);
        for (GLuint p : heavy_program) glDeleteProgram(p);
        glDeleteProgram(shadow_program);
        glDeleteFramebuffers(1, &shadow_framebuffer);
        glDeleteTextures(1, &shadow_map);
        glDeleteTextures(2, cache_term);
        glDeleteTextures(2, cache_meta);
    }

    GLint uniform(const char* name) const { return glGetUniformLocation(active, name); }

    // What one render's passes share: its size, matrices and switches (Renderer::render).
    struct Pass {
        const Scene& scene;
        const Instant& current;
        const RenderSettings& settings;
        int w, h;
        glm::mat4 unjittered, view_projection, previous_view_projection;
        glm::vec3 eye, light_direction;
        glm::mat4 light_matrix{1.0f};  // heavy: set by draw_shadow_map
        bool heavy, msaa, reusing;
        int aa;
        bool cache_usable = false;
    };
    void upload_geometry();
    void draw_shadow_map(Pass& p);
    void clear_targets(const Pass& p);
    void use(const Pass& p, GLuint shader);
    void draw_all(const Scene& scene, bool materials);
    Status shade(const Pass& p);
    void read_back(const Pass& p, Frame& frame);

    // Programs, shadow map and cache of the heavy mode, made on first use.
    Status prepare_heavy() {
        if (heavy_program[0]) return {};
        std::string vertex = shaders::kVertex;
        vertex.insert(vertex.find("uniform"), "invariant gl_Position;\n");
        for (int pass = 0; pass < 3; ++pass) {
            const std::string fragment = std::string("#version 300 es\n#define REUSE ") +
                                         (pass ? "1" : "0") + "\n#define PASS " + char('0' + pass) +
                                         "\n" + shaders::kHeavyFragment;
            REPRISE_TRY(gl::link_program(vertex.c_str(), fragment.c_str(), "heavy shading",
                                         heavy_program[pass]));
        }
        REPRISE_TRY(gl::link_program(shaders::kShadowVertex, shaders::kShadowFragment, "shadow map",
                                     shadow_program));
        glGenTextures(1, &shadow_map);
        glBindTexture(GL_TEXTURE_2D, shadow_map);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT32F, kShadowMapSize, kShadowMapSize, 0,
                     GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
        glGenFramebuffers(1, &shadow_framebuffer);
        glBindFramebuffer(GL_FRAMEBUFFER, shadow_framebuffer);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadow_map, 0);
        const GLenum none = GL_NONE;
        glDrawBuffers(1, &none);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            return Status::error("OpenGL ES: the shadow map is not renderable on this device");
        GLint draw_buffers = 0;
        glGetIntegerv(GL_MAX_DRAW_BUFFERS, &draw_buffers);
        if (draw_buffers < 5)
            return Status::error("renderer: heavy shading needs 5 draw buffers, this device has " +
                                 std::to_string(draw_buffers));
        glGenTextures(2, cache_term);
        glGenTextures(2, cache_meta);
        return {};
    }

    void set_heavy_uniforms(const Scene& s, const Instant& current, const RenderSettings& settings,
                            const glm::mat4& light_matrix, bool cache_usable);
    void read_reuse(bool reusing, const Image<uint32_t>& ids);

    void resize_cache(int w, int h) {
        for (int i = 0; i < 2; ++i) {
            gl::allocate_texture(cache_meta[i], GL_RGBA32F, w, h);
            glBindTexture(GL_TEXTURE_2D, cache_term[i]);
            glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16F, w, h, 0, GL_RGBA, GL_HALF_FLOAT, nullptr);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        }
        cache_valid = false;
    }

    bool uses_msaa(const RenderSettings& settings) const {
        const int aa = settings.shading == Shading::Heavy ? 1 : settings.aa_samples;
        return aa > 1 && msaa_has(aa) &&
               (settings.aa_method == AntiAliasing::Msaa ||
                (settings.aa_method == AntiAliasing::Auto && !software));
    }

    Status resize(int w, int h) {
        if (w == width && h == height) return {};
        if (!framebuffer) {
            glGenFramebuffers(1, &framebuffer);
            glGenTextures(3, targets);
            glGenRenderbuffers(1, &depth_buffer);
        }
        glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
        for (int i = 0; i < 3; ++i) {
            glBindTexture(GL_TEXTURE_2D, targets[i]);
            glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, nullptr);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
            glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, GL_TEXTURE_2D,
                                   targets[i], 0);
        }
        glBindRenderbuffer(GL_RENDERBUFFER, depth_buffer);
        glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH32F_STENCIL8, w,
                              h);  // stencil: reuse's passes
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER,
                                  depth_buffer);
        const GLenum buffers[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1,
                                   GL_COLOR_ATTACHMENT2};
        glDrawBuffers(3, buffers);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            return Status::error("OpenGL ES: the float G-buffer is not renderable on this device");
        width = w, height = h;
        return {};
    }

    bool msaa_has(int samples) const {
        return std::find(msaa_counts.begin(), msaa_counts.end(), samples) != msaa_counts.end();
    }

    Status prepare_msaa(int samples, int w, int h) {
        if (samples == msaa_samples && w == msaa_width && h == msaa_height) return {};
        if (!msaa_framebuffer) {
            glGenFramebuffers(1, &msaa_framebuffer);
            glGenRenderbuffers(1, &msaa_color);
            glGenRenderbuffers(1, &msaa_depth);
        }
        glBindFramebuffer(GL_FRAMEBUFFER, msaa_framebuffer);
        glBindRenderbuffer(GL_RENDERBUFFER, msaa_color);
        glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA32F, w, h);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                                  msaa_color);
        glBindRenderbuffer(GL_RENDERBUFFER, msaa_depth);
        glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT32F, w, h);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, msaa_depth);
        const GLenum buffer = GL_COLOR_ATTACHMENT0;
        glDrawBuffers(1, &buffer);
        msaa_samples = msaa_width = msaa_height = 0;
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            return Status::error("OpenGL ES: " + std::to_string(samples) +
                                 "x multisampled float colour is not renderable on this device");
        msaa_samples = samples, msaa_width = w, msaa_height = h;
        return {};
    }

    void upload_textures(const Scene& s) {
        const void* data = s.textures.empty() ? nullptr : s.textures.front().pixels.data();
        if (scene_revision == s.revision && scene_texture_data == data &&
            textures.size() == s.textures.size())
            return;
        glDeleteTextures(GLsizei(textures.size()), textures.data());
        textures.assign(s.textures.size(), 0);
        glGenTextures(GLsizei(textures.size()), textures.data());
        for (std::size_t i = 0; i < s.textures.size(); ++i) {
            const Texture& t = s.textures[i];
            glBindTexture(GL_TEXTURE_2D, textures[i]);
            glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
            // glTF rows run top to bottom and so do its UVs: upload as is, sample v as given.
            glTexImage2D(GL_TEXTURE_2D, 0, GL_SRGB8_ALPHA8, t.width, t.height, 0, GL_RGBA,
                         GL_UNSIGNED_BYTE, t.pixels.data());
            glGenerateMipmap(GL_TEXTURE_2D);
            GLint wrap = t.repeat ? GL_REPEAT : GL_CLAMP_TO_EDGE;
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, wrap);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, wrap);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER,
                            t.nearest ? GL_NEAREST : GL_LINEAR);
            if (max_anisotropy > 1.0f)
                glTexParameterf(GL_TEXTURE_2D, 0x84FE /* TEXTURE_MAX_ANISOTROPY_EXT */,
                                std::min(8.0f, max_anisotropy));
        }
        scene_revision = s.revision;
        scene_texture_data = data;
    }

    // Poses every drawn primitive at both instants into one vertex and index stream.
    void gather(const Scene& s, double time, double previous_time) {
        evaluate_pose(s, time, pose);
        evaluate_pose(s, previous_time, previous_pose);
        vertices.clear(), indices.clear(), draws.clear();
        std::vector<int> stack(s.roots.rbegin(), s.roots.rend());
        while (!stack.empty()) {
            int node = stack.back();
            stack.pop_back();
            const Node& n = s.nodes[node];
            for (auto it = n.children.rbegin(); it != n.children.rend(); ++it) stack.push_back(*it);
            if (n.mesh < 0) continue;
            bool mirrored = n.skin < 0 && glm::determinant(glm::mat3(pose.world[node])) < 0;
            float id = float(n.object_id ? n.object_id : uint32_t(node) + 1);
            for (const Primitive& p : s.meshes[n.mesh].primitives) {
                if (p.indices.empty()) continue;
                pose_vertices(s, pose, node, p, positions, normals);
                pose_vertices(s, previous_pose, node, p, previous_positions, unused);
                if (p.normals.empty()) smooth_normals(positions, p.indices, normals);
                const std::vector<glm::vec2>& uv =
                    p.material >= 0 && s.materials[p.material].texcoord == 1 ? p.uv1 : p.uv0;
                uint32_t base = uint32_t(vertices.size());
                for (std::size_t v = 0; v < positions.size(); ++v)
                    vertices.push_back({positions[v], previous_positions[v], normals[v],
                                        v < uv.size() ? uv[v] : glm::vec2(0.0f)});
                draws.push_back(
                    {GLsizei(indices.size()), GLsizei(p.indices.size()), p.material, id, mirrored});
                for (uint32_t i : p.indices) indices.push_back(base + i);
            }
        }
    }
};

void Renderer::Gpu::set_heavy_uniforms(const Scene& drawn, const Instant& current,
                                       const RenderSettings& settings,
                                       const glm::mat4& light_matrix, bool cache_usable) {
    Gpu& g = *this;
    const ReuseSettings& r = settings.reuse;
    glUniformMatrix4fv(g.uniform("u_light_matrix"), 1, GL_FALSE, glm::value_ptr(light_matrix));
    glUniform1f(g.uniform("u_shadow_texel"), 1.0f / float(kShadowMapSize));
    glUniform1i(g.uniform("u_pcf_radius"), settings.heavy_pcf_radius);
    glUniform1i(g.uniform("u_octaves"), settings.heavy_octaves);
    const int lights = int(std::min<std::size_t>(drawn.point_lights.size(), 16));
    glm::vec3 light_positions[16], light_colors[16];
    for (int i = 0; i < lights; ++i)
        light_positions[i] = drawn.point_lights[i].position,
        light_colors[i] = drawn.point_lights[i].color;
    glUniform1i(g.uniform("u_point_count"), lights);
    if (lights > 0) {
        glUniform3fv(g.uniform("u_point_position"), lights, glm::value_ptr(light_positions[0]));
        glUniform3fv(g.uniform("u_point_color"), lights, glm::value_ptr(light_colors[0]));
    }
    glUniform1i(g.uniform("u_reuse"), int(r.mode));
    glUniform1i(g.uniform("u_cache_valid"), cache_usable);
    glUniform1i(g.uniform("u_frame"), g.reuse_frame);
    glUniform1i(g.uniform("u_refresh"), int(r.refresh));
    glUniform1i(g.uniform("u_period"), r.period);
    int rows = 1;
    for (int d = 1; d * d <= r.period; ++d)
        if (r.period % d == 0) rows = d;
    glUniform2i(g.uniform("u_tiles"), r.period / rows, rows);
    glUniform1i(g.uniform("u_interleave_step"),
                std::max(1, int(std::lround(std::sqrt(double(r.period))))));
    glUniform1f(g.uniform("u_threshold"), r.threshold);
    glUniform1i(g.uniform("u_filter_radius"), r.filter_radius);
    // One step of a 24-bit Z-buffer, in the cache's depth key (heavy_shaders.hpp).
    const bool orthographic = current.projection[3][3] == 1.0f;
    const float inverse_range =
        orthographic
            ? 1.0f
            : 1.0f / current.near - (std::isfinite(current.far) ? 1.0f / current.far : 0.0f);
    glUniform1i(g.uniform("u_orthographic"), orthographic);
    glUniform1f(g.uniform("u_epsilon"), r.depth_epsilon / 16777215.0f * inverse_range);
    glUniform1f(g.uniform("u_smoothing"), r.smoothing);
    glUniform1i(g.uniform("u_shadow_map"), 1);
    glUniform1i(g.uniform("u_cache_term"), 2);
    glUniform1i(g.uniform("u_cache_meta"), 3);
    const int previous = g.cache_slot ^ 1;
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, g.shadow_map);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, g.cache_term[previous]);
    glActiveTexture(GL_TEXTURE3);
    glBindTexture(GL_TEXTURE_2D, g.cache_meta[previous]);
}

// Statistics and per-pixel maps of reuse (everything is shaded without it).
void Renderer::Gpu::read_reuse(bool reusing, const Image<uint32_t>& ids) {
    Gpu& g = *this;
    const int w = ids.width(), h = ids.height();
    ReuseStats& s = g.stats;
    s.covered = s.hits = s.reused = s.shaded = 0;
    g.maps.status.resize(w, h);
    g.maps.age.resize(w, h);
    if (!reusing) {
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const bool covered = ids(x, y) != 0;
                g.maps.status(x, y) = covered ? kReuseMiss : kReuseBackground;
                g.maps.age(x, y) = 0;
                s.covered += covered;
            }
        s.shaded = s.covered;
        return;
    }
    glReadBuffer(GL_COLOR_ATTACHMENT4);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, g.readback.data());
    for (int y = 0; y < h; ++y) {
        const glm::vec4* row = g.readback.data() + std::size_t(h - 1 - y) * w;
        for (int x = 0; x < w; ++x) {
            const glm::vec4 meta = row[x];  // depth, id, age, gradient (< 0: shaded on a miss)
            const uint8_t status = meta.y == 0.0f  ? kReuseBackground
                                   : meta.z > 0.0f ? kReuseHit
                                   : meta.w < 0.0f ? kReuseMiss
                                                   : kReuseRefresh;
            g.maps.status(x, y) = status;
            g.maps.age(x, y) = uint8_t(std::min(meta.z, 255.0f));
            s.covered += status != kReuseBackground;
            s.hits += status == kReuseHit || status == kReuseRefresh;
            s.reused += status == kReuseHit;
            s.shaded += status == kReuseMiss || status == kReuseRefresh;
        }
    }
}

bool aa_samples_valid(int samples) {
    return samples == 1 || supersample_positions(samples) != nullptr;
}

bool lowres_factor_valid(int factor) { return factor == 1 || factor == 2 || factor == 4; }

glm::ivec2 lowres_size(int width, int height, int factor) {
    REPRISE_ASSERT(lowres_factor_valid(factor) && width > 0 && height > 0);
    if (factor == 1) return {width, height};
    return {(width + 1) / 2, factor == 4 ? (height + 1) / 2 : height};
}

glm::vec2 lowres_jitter(int width, int height, int factor, int64_t index) {
    const glm::ivec2 low = lowres_size(width, height, factor);
    const glm::vec2 footprint(float(width) / float(low.x), float(height) / float(low.y));
    // Offsets of the sample within its low pixel, as fractions of the footprint: 2x1 alternates
    // left/right; 2x2 visits the diagonal first so consecutive frames are far apart.
    static constexpr glm::vec2 kCycle2x2[4] = {
        {0.25f, 0.25f}, {0.75f, 0.75f}, {0.75f, 0.25f}, {0.25f, 0.75f}};
    static constexpr glm::vec2 kCycle2x1[2] = {{0.25f, 0.5f}, {0.75f, 0.5f}};
    if (factor == 1) return glm::vec2(0.0f);
    const int64_t phase = index < 0 ? -index : index;
    const glm::vec2 at = factor == 4 ? kCycle2x2[phase % 4] : kCycle2x1[phase % 2];
    return (at - 0.5f) * footprint;
}

glm::vec3 light_direction_at(const Light& light, double time) {
    if (light.orbit == 0.0f) return light.direction;
    const float angle = float(double(light.orbit) * time);
    return glm::angleAxis(angle, glm::vec3(0, 1, 0)) * light.direction;
}

bool cut_between(const CameraPath& path, const Instant& before, const Instant& now) {
    return path.motion == CameraMotion::Cut && before.time < path.cut_time &&
           now.time >= path.cut_time;
}

Instant instant_on_path(const CameraPath& path, const Scene& scene, double time, int width,
                        int height) {
    return {.time = time,
            .view = camera_view(path, scene, time),
            .projection = camera_projection(path.model, width, height),
            .near = path.model.znear,
            .far = path.model.zfar > 0 ? path.model.zfar : std::numeric_limits<float>::infinity()};
}

Renderer::Renderer() : gpu_(std::make_unique<Gpu>()) {}
Renderer::~Renderer() = default;

const std::string& Renderer::device() const { return gpu_->context->description(); }
std::uint64_t render_memory(const RenderSettings& settings, bool msaa, int lowres_factor) {
    REPRISE_ASSERT(settings.width >= 0 && settings.height >= 0 &&
                   lowres_factor_valid(lowres_factor));
    constexpr std::uint64_t kGbuffer = 3 * 16 + 8, kReadback = 16, kFrame = 16 + 4 + 8 + 12 + 4;
    const std::uint64_t pixels = std::uint64_t(settings.width) * std::uint64_t(settings.height);
    std::uint64_t per_pixel = kGbuffer + kReadback + kFrame;
    if (msaa) per_pixel += std::uint64_t(settings.aa_samples) * (16 + 4);
    std::uint64_t fixed = 0;
    if (settings.shading == Shading::Heavy) {
        per_pixel += 2 * (16 + 8) + 2;  // two cache slots (term, meta), status and age maps
        fixed += std::uint64_t(kShadowMapSize) * kShadowMapSize * 4;
    }
    std::uint64_t low = 0;
    if (lowres_factor > 1) {
        const glm::ivec2 size = lowres_size(settings.width, settings.height, lowres_factor);
        low = std::uint64_t(size.x) * std::uint64_t(size.y) * (kFrame + 16);
    }
    return pixels * per_pixel + low + fixed;
}

Status Renderer::check_settings(const RenderSettings& settings, int lowres_factor) const {
    const Gpu& g = *gpu_;
    const std::string size = std::to_string(settings.width) + "x" + std::to_string(settings.height);
    if (settings.width > g.max_target_size || settings.height > g.max_target_size)
        return Status::error("render " + size +
                             ": larger than this device's largest render target (" +
                             std::to_string(g.max_target_size) + " pixels a side)");
    if (!lowres_factor_valid(lowres_factor))
        return Status::error("render: low-resolution factor " + std::to_string(lowres_factor) +
                             " must be 2 or 4");
    const bool msaa = g.uses_msaa(settings);
    std::string what = "render " + size;
    if (msaa) what += " with " + std::to_string(settings.aa_samples) + "x MSAA";
    if (lowres_factor > 1) what += " and 1/" + std::to_string(lowres_factor) + " colour";
    return check_memory(render_memory(settings, msaa, lowres_factor), what);
}

bool Renderer::msaa_supported(int samples) const {
    return gpu_->msaa_has(samples) && !gpu_->software;
}
const ReuseStats& Renderer::reuse_stats() const { return gpu_->stats; }
const ReuseMaps& Renderer::reuse_maps() const { return gpu_->maps; }
void Renderer::drop_reuse_cache() { gpu_->cache_valid = false; }

Status Renderer::create(std::unique_ptr<Renderer>& renderer) {
    std::unique_ptr<Renderer> r(new Renderer());
    Gpu& g = *r->gpu_;
    REPRISE_TRY(gl::Context::create(g.context));
    REPRISE_TRY(gl::link_program(shaders::kVertex, shaders::kFragment, "G-buffer", g.program));
    glGenVertexArrays(1, &g.vertex_array);
    glGenBuffers(1, &g.vertex_buffer);
    glGenBuffers(1, &g.index_buffer);
    glBindVertexArray(g.vertex_array);
    glBindBuffer(GL_ARRAY_BUFFER, g.vertex_buffer);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.index_buffer);
    const GLsizei stride = sizeof(Vertex);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, (void*)offsetof(Vertex, position));
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride, (void*)offsetof(Vertex, previous));
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, stride, (void*)offsetof(Vertex, normal));
    glEnableVertexAttribArray(3);
    glVertexAttribPointer(3, 2, GL_FLOAT, GL_FALSE, stride, (void*)offsetof(Vertex, uv));
    const char* extensions = reinterpret_cast<const char*>(glGetString(GL_EXTENSIONS));
    if (extensions &&
        std::string(extensions).find("GL_EXT_texture_filter_anisotropic") != std::string::npos)
        glGetFloatv(0x84FF /* MAX_TEXTURE_MAX_ANISOTROPY_EXT */, &g.max_anisotropy);
    GLint max_renderbuffer = 0, max_texture = 0;
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_renderbuffer);
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_texture);
    g.max_target_size = std::min(max_renderbuffer, max_texture);
    GLint counts = 0;
    glGetInternalformativ(GL_RENDERBUFFER, GL_RGBA32F, GL_NUM_SAMPLE_COUNTS, 1, &counts);
    g.msaa_counts.assign(std::size_t(std::clamp(counts, 0, 32)), 0);
    if (!g.msaa_counts.empty())
        glGetInternalformativ(GL_RENDERBUFFER, GL_RGBA32F, GL_SAMPLES,
                              GLsizei(g.msaa_counts.size()), g.msaa_counts.data());
    while (glGetError() != GL_NO_ERROR) g.msaa_counts.clear();
    const char* name = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    g.software = name && (std::string(name).find("llvmpipe") != std::string::npos ||
                          std::string(name).find("softpipe") != std::string::npos);
    // Anisotropic filtering on hardware only: on llvmpipe (Mesa 22.3) it made `bench stream` 2.5x
    // slower, and in about one run of three a rasteriser thread never finished a draw.
    if (g.software) g.max_anisotropy = 0.0f;
    renderer = std::move(r);
    return {};
}

Status Renderer::render(const Scene& scene, const Instant& current, const Instant& previous,
                        const RenderSettings& settings, Frame& frame) {
    Gpu& g = *gpu_;
    const int w = settings.width, h = settings.height;
    REPRISE_TRY(check_image_size(w, h, "renderer"));
    if (!aa_samples_valid(settings.aa_samples))
        return Status::error("renderer: anti-aliasing samples " +
                             std::to_string(settings.aa_samples) + " must be 1, 2, 4, 8 or 16");
    REPRISE_TRY(check_settings(settings));
    g.context->make_current();
    REPRISE_TRY(g.resize(w, h));
    g.upload_textures(scene);
    g.gather(scene, current.time, previous.time);

    const bool heavy = settings.shading == Shading::Heavy;
    // Pixel p samples the unjittered image at p + jitter: shift the image by -jitter.
    const glm::mat4 unjittered = current.projection * current.view;
    Gpu::Pass pass{.scene = scene,
                   .current = current,
                   .settings = settings,
                   .w = w,
                   .h = h,
                   .unjittered = unjittered,
                   .view_projection = shifted(unjittered, current.jitter, w, h),
                   .previous_view_projection = previous.projection * previous.view,
                   .eye = glm::vec3(glm::inverse(current.view)[3]),
                   .light_direction = light_direction_at(scene.light, current.time),
                   .heavy = heavy,
                   .msaa = g.uses_msaa(settings),
                   .reusing = heavy && settings.reuse.mode != Reuse::Off,
                   .aa = heavy ? 1 : settings.aa_samples};
    if (heavy) {
        REPRISE_TRY(check_heavy_settings(settings));
        REPRISE_TRY(g.prepare_heavy());
        if (g.cache_width != w || g.cache_height != h) {
            g.resize_cache(w, h);
            g.cache_width = w, g.cache_height = h;
        }
    }
    pass.cache_usable = pass.reusing && g.cache_valid && !current.cut &&
                        g.cache_scene == scene.revision && previous.time == g.cache_time &&
                        previous.view == g.cache_view;

    g.upload_geometry();
    if (heavy) g.draw_shadow_map(pass);
    g.clear_targets(pass);
    REPRISE_TRY(g.shade(pass));
    g.read_back(pass, frame);
    if (heavy) g.read_reuse(pass.reusing, frame.id);
    if (pass.reusing) {
        g.cache_valid = true;
        g.cache_time = current.time;
        g.cache_view = current.view;
        g.cache_scene = scene.revision;
        g.cache_slot ^= 1;
        ++g.reuse_frame;
    }
    GLenum error = glGetError();
    if (error != GL_NO_ERROR)
        return Status::error("OpenGL ES error 0x" + std::to_string(error) + " while rendering");

    Camera& c = frame.camera;
    c.view = current.view;
    c.projection = current.projection;
    c.prev_view = previous.view;
    c.prev_projection = previous.projection;
    c.near = current.near;
    c.far = current.far;
    c.jitter = current.jitter;
    c.time = current.time;
    // Only a path knows that no cut came (render_frame); a caller's instants may jump.
    c.cut = current.cut ? Cut::Yes : Cut::Unknown;
    if (scene.hud)
        draw_hud(current.time, w, h, frame.ui);
    else
        frame.ui.clear();
    return {};
}

void Renderer::Gpu::upload_geometry() {
    glBindVertexArray(vertex_array);
    glBindBuffer(GL_ARRAY_BUFFER, vertex_buffer);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(vertices.size() * sizeof(Vertex)), vertices.data(),
                 GL_STREAM_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_buffer);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(indices.size() * sizeof(uint32_t)),
                 indices.data(), GL_STREAM_DRAW);
}

// Heavy shading: the key light's depth, seen from the light.
void Renderer::Gpu::draw_shadow_map(Pass& p) {
    p.light_matrix = shadow_light_matrix(vertices, p.light_direction);
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_framebuffer);
    glViewport(0, 0, kShadowMapSize, kShadowMapSize);
    glClearDepthf(1.0f);
    glClear(GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);
    glUseProgram(shadow_program);
    glUniformMatrix4fv(glGetUniformLocation(shadow_program, "u_light_matrix"), 1, GL_FALSE,
                       glm::value_ptr(p.light_matrix));
    for (const Draw& d : draws)
        glDrawElements(GL_TRIANGLES, d.index_count, GL_UNSIGNED_INT,
                       (void*)(std::size_t(d.first_index) * sizeof(uint32_t)));
}

// The G-buffer targets (and the reuse cache's, when reusing) bound and cleared.
void Renderer::Gpu::clear_targets(const Pass& p) {
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    glViewport(0, 0, p.w, p.h);
    const int slot = cache_slot;
    if (p.reusing) {
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT3, GL_TEXTURE_2D,
                               cache_term[slot], 0);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT4, GL_TEXTURE_2D,
                               cache_meta[slot], 0);
        const GLenum buffers[5] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2,
                                   GL_COLOR_ATTACHMENT3, GL_COLOR_ATTACHMENT4};
        glDrawBuffers(5, buffers);
        const glm::vec4 empty_meta(-1.0f, 0.0f, 0.0f, 0.0f);
        glClearBufferfv(GL_COLOR, 3, glm::value_ptr(glm::vec4(0.0f)));
        glClearBufferfv(GL_COLOR, 4, glm::value_ptr(empty_meta));
    } else {
        const GLenum buffers[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1,
                                   GL_COLOR_ATTACHMENT2};
        glDrawBuffers(3, buffers);
    }
    const glm::vec4 sky(p.scene.background, 0.0f), zero(0.0f);
    glClearBufferfv(GL_COLOR, 0, glm::value_ptr(sky));
    glClearBufferfv(GL_COLOR, 1, glm::value_ptr(zero));
    glClearBufferfv(GL_COLOR, 2, glm::value_ptr(zero));
    glClearDepthf(1.0f);
    glClearStencil(0);
    glClear(GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_BLEND);
}

// Everything a program of the main pass needs besides the per-draw material.
void Renderer::Gpu::use(const Pass& p, GLuint shader) {
    active = shader;
    glUseProgram(shader);
    glUniformMatrix4fv(uniform("u_view_projection"), 1, GL_FALSE,
                       glm::value_ptr(p.view_projection));
    glUniformMatrix4fv(uniform("u_unjittered_view_projection"), 1, GL_FALSE,
                       glm::value_ptr(p.unjittered));
    glUniformMatrix4fv(uniform("u_view"), 1, GL_FALSE, glm::value_ptr(p.current.view));
    glUniformMatrix4fv(uniform("u_previous_view_projection"), 1, GL_FALSE,
                       glm::value_ptr(p.previous_view_projection));
    glUniform2f(uniform("u_size"), float(p.w), float(p.h));
    glUniform3fv(uniform("u_eye"), 1, glm::value_ptr(p.eye));
    glUniform3fv(uniform("u_light_direction"), 1, glm::value_ptr(p.light_direction));
    glUniform3fv(uniform("u_light_color"), 1, glm::value_ptr(p.scene.light.color));
    glUniform3fv(uniform("u_ambient"), 1, glm::value_ptr(p.scene.light.ambient));
    glUniform1i(uniform("u_lit"), p.settings.shading == Shading::Lit);
    glUniform1i(uniform("u_texture"), 0);
    glUniform1f(uniform("u_lod_bias"),
                std::isfinite(p.settings.texture_lod_bias) ? p.settings.texture_lod_bias : 0.0f);
    if (p.heavy) set_heavy_uniforms(p.scene, p.current, p.settings, p.light_matrix, p.cache_usable);
    glActiveTexture(GL_TEXTURE0);
}

void Renderer::Gpu::draw_all(const Scene& scene, bool materials) {
    static const Material fallback;
    const GLint base_color = uniform("u_base_color"), textured = uniform("u_textured"),
                specular = uniform("u_specular"), shininess = uniform("u_shininess"),
                mirror = uniform("u_mirror"), id = uniform("u_id");
    for (const Draw& d : draws) {
        const Material& m = d.material >= 0 ? scene.materials[d.material] : fallback;
        if (materials) {
            glUniform4fv(base_color, 1, glm::value_ptr(m.base_color));
            glUniform1i(textured, m.base_color_texture >= 0);
            if (m.base_color_texture >= 0)
                glBindTexture(GL_TEXTURE_2D, textures[m.base_color_texture]);
            glUniform1f(specular, m.specular);
            glUniform1f(shininess, m.shininess);
            glUniform1f(mirror, m.mirror);
            glUniform1f(id, d.id);
        }
        if (m.double_sided)
            glDisable(GL_CULL_FACE);
        else
            glEnable(GL_CULL_FACE);
        glFrontFace(d.mirrored ? GL_CW : GL_CCW);
        glDrawElements(GL_TRIANGLES, d.index_count, GL_UNSIGNED_INT,
                       (void*)(std::size_t(d.first_index) * sizeof(uint32_t)));
    }
}

// The main pass: lit (single sample, MSAA resolved, or supersampled) or heavy (a depth
// pre-pass, then full shading or the reuse cache's hit and miss passes).
Status Renderer::Gpu::shade(const Pass& p) {
    const auto shading_start = std::chrono::steady_clock::now();
    const double shading_cpu_start = process_cpu_ms();
    const int w = p.w, h = p.h, aa = p.aa;
    const glm::vec4 sky(p.scene.background, 0.0f), zero(0.0f);
    if (!p.heavy) {
        use(p, program);
        draw_all(p.scene, true);
        if (p.msaa) {
            // The same draws into the multisampled target, resolved into the colour target.
            REPRISE_TRY(prepare_msaa(aa, w, h));
            glBindFramebuffer(GL_FRAMEBUFFER, msaa_framebuffer);
            glClearBufferfv(GL_COLOR, 0, glm::value_ptr(sky));
            glClear(GL_DEPTH_BUFFER_BIT);
            draw_all(p.scene, true);
            glBindFramebuffer(GL_DRAW_FRAMEBUFFER, framebuffer);
            const GLenum color_only = GL_COLOR_ATTACHMENT0;
            glDrawBuffers(1, &color_only);
            glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
            glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
        } else if (aa > 1) {
            // Supersampling: the mean of `aa` passes, each sampling around p + jitter + offset;
            // sky where a pass drew nothing is added on read-back from the summed coverage.
            // Each pass lays depth first, then adds the one fragment per pixel at that depth
            // (the stencil admits a single one where coplanar surfaces tie).
            const GLenum color_only = GL_COLOR_ATTACHMENT0;
            glDrawBuffers(1, &color_only);
            glClearBufferfv(GL_COLOR, 0, glm::value_ptr(zero));
            glBlendFunc(GL_CONSTANT_ALPHA, GL_ONE);
            glBlendColor(0.0f, 0.0f, 0.0f, 1.0f / float(aa));
            glStencilFunc(GL_EQUAL, 0, 0xff);
            glStencilOp(GL_KEEP, GL_KEEP, GL_INCR);
            const GLint matrix = uniform("u_view_projection");
            const glm::vec2* offsets = supersample_positions(aa);
            for (int i = 0; i < aa; ++i) {
                const glm::mat4 sample =
                    shifted(p.unjittered, p.current.jitter + offsets[i] / 16.0f, w, h);
                glUniformMatrix4fv(matrix, 1, GL_FALSE, glm::value_ptr(sample));
                glDepthMask(GL_TRUE);  // glClear obeys the write mask
                glClear(GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
                glDepthFunc(GL_LESS);
                glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
                draw_all(p.scene, false);
                glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
                glDepthFunc(GL_EQUAL);
                glDepthMask(GL_FALSE);
                glEnable(GL_STENCIL_TEST);
                glEnable(GL_BLEND);
                draw_all(p.scene, true);
                glDisable(GL_BLEND);
                glDisable(GL_STENCIL_TEST);
            }
            glDepthFunc(GL_LESS);
            glDepthMask(GL_TRUE);
        }
        return {};
    }
    // Depth pre-pass: each pixel then runs the heavy shader once.
    active = shadow_program;
    glUseProgram(shadow_program);
    glUniformMatrix4fv(uniform("u_light_matrix"), 1, GL_FALSE, glm::value_ptr(p.view_projection));
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    draw_all(p.scene, false);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_FALSE);
    if (!p.reusing) {
        use(p, heavy_program[0]);
        draw_all(p.scene, true);
    } else {
        // Nehab's two-pass control flow with the stencil in place of a depth shift: the hit
        // pass marks what it reused; the miss pass shades the rest and is culled early
        // wherever the hit pass covered a whole block.
        glEnable(GL_STENCIL_TEST);
        glStencilMask(0xff);
        glStencilFunc(GL_ALWAYS, 1, 0xff);
        glStencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);
        use(p, heavy_program[1]);
        draw_all(p.scene, true);
        glStencilFunc(GL_EQUAL, 0, 0xff);
        glStencilOp(GL_KEEP, GL_KEEP, GL_KEEP);
        use(p, heavy_program[2]);
        draw_all(p.scene, true);
        glDisable(GL_STENCIL_TEST);
    }
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LESS);
    glFinish();
    stats.shading_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - shading_start)
            .count();
    stats.shading_cpu_ms = process_cpu_ms() - shading_cpu_start;
    return {};
}

// Read back, turning GL's bottom-up rows into top-down images; the background's depth and
// motion are computed here.
void Renderer::Gpu::read_back(const Pass& p, Frame& frame) {
    const int w = p.w, h = p.h;
    if (frame.width() != w || frame.height() != h || frame.depth.empty() || frame.id.empty()) {
        frame.color.resize(w, h);
        frame.depth.resize(w, h);
        frame.motion.resize(w, h);
        frame.normal.resize(w, h);
        frame.id.resize(w, h);
    }
    readback.resize(std::size_t(w) * h);
    auto read = [&](int attachment, auto&& store) {
        glReadBuffer(GL_COLOR_ATTACHMENT0 + attachment);
        glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, readback.data());
        for (int y = 0; y < h; ++y) {
            const glm::vec4* row = readback.data() + std::size_t(h - 1 - y) * w;
            for (int x = 0; x < w; ++x) store(x, y, row[x]);
        }
    };
    const glm::vec3 background = p.scene.background;
    if (p.aa > 1 && !p.msaa)
        read(0, [&](int x, int y, glm::vec4 v) {
            frame.color(x, y) = glm::vec4(glm::vec3(v) + (1.0f - v.a) * background, v.a);
        });
    else
        read(0, [&](int x, int y, glm::vec4 v) { frame.color(x, y) = v; });
    read(2, [&](int x, int y, glm::vec4 v) { frame.normal(x, y) = glm::vec3(v); });
    // Background: depth +inf, motion of the point at infinity seen through this pixel, with
    // both ends projected the same way (a still camera gives exactly 0).
    // Orthographic cameras see the far plane instead (w = 1: a point, not a direction).
    const double point = p.current.projection[3][3] == 1.0f ? 1.0 : 0.0;
    const glm::dmat4 unproject = glm::inverse(glm::dmat4(p.view_projection));
    auto to_pixels = [&](const glm::mat4& matrix, glm::dvec4 world, glm::dvec2& pixel) {
        glm::dvec4 clip = glm::dmat4(matrix) * world;
        pixel = {(clip.x / clip.w * 0.5 + 0.5) * w, (0.5 - 0.5 * clip.y / clip.w) * h};
        return clip.w > 0.0;
    };
    const float nan = std::numeric_limits<float>::quiet_NaN();
    read(1, [&](int x, int y, glm::vec4 v) {
        if (v.w != 0.0f) {
            frame.depth(x, y) = v.x;
            bool behind = std::abs(v.y) >= kNoPrevious;
            frame.motion(x, y) = behind ? glm::vec2(nan) : glm::vec2(v.y, v.z);
            frame.id(x, y) = uint32_t(v.w);
            return;
        }
        frame.depth(x, y) = std::numeric_limits<float>::infinity();
        frame.id(x, y) = 0;
        glm::dvec2 ndc(2.0 * (x + 0.5) / w - 1.0, 1.0 - 2.0 * (y + 0.5) / h);
        glm::dvec4 a = unproject * glm::dvec4(ndc, -1.0, 1.0),
                   b = unproject * glm::dvec4(ndc, point, 1.0);
        glm::dvec4 world =
            point == 1.0 ? b / b.w : glm::dvec4(glm::dvec3(b) / b.w - glm::dvec3(a) / a.w, 0.0);
        glm::dvec2 here, there;
        bool visible = to_pixels(p.unjittered, world, here) &&
                       to_pixels(p.previous_view_projection, world, there);
        frame.motion(x, y) = visible ? glm::vec2(there - here) : glm::vec2(nan);
    });
    // Coverage stays the pixel centre's, as without anti-aliasing.
    if (p.aa > 1)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) frame.color(x, y).a = frame.id(x, y) != 0 ? 1.0f : 0.0f;
}

Status Renderer::render_frame(const Scene& scene, const CameraPath& path, int index, double fps,
                              const RenderSettings& settings, Frame& frame) {
    REPRISE_ASSERT(fps > 0);
    const int w = settings.width, h = settings.height;
    Instant now = instant_on_path(path, scene, index / fps, w, h);
    const Instant before = instant_on_path(path, scene, (index - 1) / fps, w, h);
    now.cut = cut_between(path, before, now);
    REPRISE_TRY(render(scene, now, before, settings, frame));
    frame.camera.cut = now.cut ? Cut::Yes : Cut::No;
    frame.fps = fps;
    return {};
}

Status Renderer::render_frame_lowres(const Scene& scene, const CameraPath& path, int index,
                                     double fps, const RenderSettings& settings, int factor,
                                     Frame& frame, Image<glm::vec4>& low_color, glm::vec2& jitter) {
    REPRISE_ASSERT(fps > 0);
    REPRISE_TRY(check_image_size(settings.width, settings.height, "renderer"));
    Instant now = instant_on_path(path, scene, index / fps, settings.width, settings.height);
    const Instant before =
        instant_on_path(path, scene, (index - 1) / fps, settings.width, settings.height);
    now.cut = cut_between(path, before, now);
    REPRISE_TRY(
        render_lowres(scene, now, before, settings, factor, index, frame, low_color, jitter));
    frame.camera.cut = now.cut ? Cut::Yes : Cut::No;
    frame.fps = fps;
    return {};
}

Status Renderer::render_lowres(const Scene& scene, const Instant& current, const Instant& previous,
                               const RenderSettings& settings, int factor, int64_t jitter_index,
                               Frame& frame, Image<glm::vec4>& low_color, glm::vec2& jitter) {
    REPRISE_ASSERT(lowres_factor_valid(factor));
    REPRISE_TRY(check_image_size(settings.width, settings.height, "renderer"));
    REPRISE_TRY(check_settings(settings, factor));
    // Single samples at full resolution too: the upsampler rebuilds the point-sampled image from
    // jittered point samples, and that image is what its output is compared with.
    RenderSettings full_settings = settings;
    full_settings.aa_samples = 1;
    REPRISE_TRY(render(scene, current, previous, full_settings, frame));
    const glm::ivec2 low = lowres_size(settings.width, settings.height, factor);
    // Relative to the unjittered full image (the full frame's own jitter, usually 0, included).
    jitter = current.jitter + lowres_jitter(settings.width, settings.height, factor, jitter_index);
    const glm::vec2 footprint(float(settings.width) / float(low.x),
                              float(settings.height) / float(low.y));
    // The same frustum (projection of the full size) at the low size; the jitter in low pixels.
    Instant now = current;
    now.jitter = jitter / footprint;
    RenderSettings low_settings = full_settings;
    low_settings.width = low.x;
    low_settings.height = low.y;
    // Texture detail about as the full resolution picks it. (Scaling the screen derivatives
    // through textureGrad would be exact but matched the full render worse on llvmpipe: 34.3
    // against 35.4 dB for the composed 2x2 cycle of a still camera, probably anisotropy.)
    low_settings.texture_lod_bias =
        settings.texture_lod_bias - 0.5f * std::log2(footprint.x * footprint.y);
    Frame& scratch = gpu_->lowres_scratch;
    REPRISE_TRY(render(scene, now, previous, low_settings, scratch));
    low_color.resize(low.x, low.y);
    std::copy(scratch.color.data(), scratch.color.data() + scratch.color.pixel_count(),
              low_color.data());
    return {};
}

}  // namespace reprise::server
