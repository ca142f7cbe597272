#include "reprise/server/renderer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <GLES3/gl32.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "gbuffer_shaders.hpp"
#include "reprise/server/animation.hpp"
#include "reprise/server/gl_context.hpp"

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

Status compile(GLenum type, const char* source, GLuint& shader) {
    shader = glCreateShader(type);
    glShaderSource(shader, 1, &source, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (ok) return {};
    char log[2048] = {};
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    return Status::error(std::string("OpenGL ES: shader does not compile: ") + log);
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

}  // namespace

struct Renderer::Gpu {
    std::unique_ptr<GlContext> context;
    GLuint program = 0;
    GLuint framebuffer = 0;
    GLuint targets[3] = {};  // colour, (depth, motion, id), normal
    GLuint depth_buffer = 0;
    GLuint vertex_array = 0, vertex_buffer = 0, index_buffer = 0;
    int width = 0, height = 0;
    float max_anisotropy = 0.0f;
    Frame lowres_scratch;  // the low-resolution render of render_frame_lowres
    // Textures of the scene last drawn, recognised by its address and its texture storage.
    const Scene* scene = nullptr;
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
        glDeleteBuffers(1, &vertex_buffer);
        glDeleteBuffers(1, &index_buffer);
        glDeleteVertexArrays(1, &vertex_array);
        glDeleteProgram(program);
    }

    GLint uniform(const char* name) const { return glGetUniformLocation(program, name); }

    Status resize(int w, int h) {
        if (w == width && h == height) return {};
        GLint max_size = 0;
        glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
        if (w > max_size || h > max_size)
            return Status::error("renderer: " + std::to_string(w) + "x" + std::to_string(h) +
                                 " exceeds this device's largest render target " +
                                 std::to_string(max_size));
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
        glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_buffer);
        const GLenum buffers[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
        glDrawBuffers(3, buffers);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            return Status::error("OpenGL ES: the float G-buffer is not renderable on this device");
        width = w, height = h;
        return {};
    }

    void upload_textures(const Scene& s) {
        const void* data = s.textures.empty() ? nullptr : s.textures.front().pixels.data();
        if (scene == &s && scene_texture_data == data && textures.size() == s.textures.size())
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
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, t.nearest ? GL_NEAREST : GL_LINEAR);
            if (max_anisotropy > 1.0f)
                glTexParameterf(GL_TEXTURE_2D, 0x84FE /* TEXTURE_MAX_ANISOTROPY_EXT */,
                                std::min(8.0f, max_anisotropy));
        }
        scene = &s;
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
                const std::vector<glm::vec2>& uv = p.material >= 0 &&
                    s.materials[p.material].texcoord == 1 ? p.uv1 : p.uv0;
                uint32_t base = uint32_t(vertices.size());
                for (std::size_t v = 0; v < positions.size(); ++v)
                    vertices.push_back({positions[v], previous_positions[v], normals[v],
                                        v < uv.size() ? uv[v] : glm::vec2(0.0f)});
                draws.push_back({GLsizei(indices.size()), GLsizei(p.indices.size()), p.material, id,
                                 mirrored});
                for (uint32_t i : p.indices) indices.push_back(base + i);
            }
        }
    }
};

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
    static constexpr glm::vec2 kCycle2x2[4] = {{0.25f, 0.25f}, {0.75f, 0.75f}, {0.75f, 0.25f}, {0.25f, 0.75f}};
    static constexpr glm::vec2 kCycle2x1[2] = {{0.25f, 0.5f}, {0.75f, 0.5f}};
    if (factor == 1) return glm::vec2(0.0f);
    const int64_t phase = index < 0 ? -index : index;
    const glm::vec2 at = factor == 4 ? kCycle2x2[phase % 4] : kCycle2x1[phase % 2];
    return (at - 0.5f) * footprint;
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

Status Renderer::create(std::unique_ptr<Renderer>& renderer) {
    std::unique_ptr<Renderer> r(new Renderer());
    Gpu& g = *r->gpu_;
    REPRISE_TRY(GlContext::create(g.context));
    GLuint vs = 0, fs = 0;
    Status status = compile(GL_VERTEX_SHADER, shaders::kVertex, vs);
    if (status.ok()) status = compile(GL_FRAGMENT_SHADER, shaders::kFragment, fs);
    if (status.ok()) {
        g.program = glCreateProgram();
        glAttachShader(g.program, vs);
        glAttachShader(g.program, fs);
        glLinkProgram(g.program);
        GLint linked = 0;
        glGetProgramiv(g.program, GL_LINK_STATUS, &linked);
        if (!linked) status = Status::error("OpenGL ES: the G-buffer program does not link");
    }
    glDeleteShader(vs);
    glDeleteShader(fs);
    REPRISE_TRY(status);
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
    if (extensions && std::string(extensions).find("GL_EXT_texture_filter_anisotropic") !=
                          std::string::npos)
        glGetFloatv(0x84FF /* MAX_TEXTURE_MAX_ANISOTROPY_EXT */, &g.max_anisotropy);
    renderer = std::move(r);
    return {};
}

Status Renderer::render(const Scene& scene, const Instant& current, const Instant& previous,
                        const RenderSettings& settings, Frame& frame) {
    Gpu& g = *gpu_;
    const int w = settings.width, h = settings.height;
    REPRISE_TRY(check_image_size(w, h, "renderer"));
    g.context->make_current();
    REPRISE_TRY(g.resize(w, h));
    g.upload_textures(scene);
    g.gather(scene, current.time, previous.time);

    // Pixel p samples the unjittered image at p + jitter: shift the image by -jitter.
    glm::mat4 shift = glm::translate(glm::mat4(1.0f),
                                     glm::vec3(-2.0f * current.jitter.x / float(w),
                                               2.0f * current.jitter.y / float(h), 0.0f));
    glm::mat4 view_projection = shift * current.projection * current.view;
    glm::mat4 previous_view_projection = previous.projection * previous.view;
    glm::vec3 eye = glm::vec3(glm::inverse(current.view)[3]);

    glBindFramebuffer(GL_FRAMEBUFFER, g.framebuffer);
    glViewport(0, 0, w, h);
    const glm::vec4 sky(scene.background, 0.0f), zero(0.0f);
    glClearBufferfv(GL_COLOR, 0, glm::value_ptr(sky));
    glClearBufferfv(GL_COLOR, 1, glm::value_ptr(zero));
    glClearBufferfv(GL_COLOR, 2, glm::value_ptr(zero));
    glClearDepthf(1.0f);
    glClear(GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_BLEND);

    glUseProgram(g.program);
    glUniformMatrix4fv(g.uniform("u_view_projection"), 1, GL_FALSE, glm::value_ptr(view_projection));
    const glm::mat4 unjittered = current.projection * current.view;
    glUniformMatrix4fv(g.uniform("u_unjittered_view_projection"), 1, GL_FALSE,
                       glm::value_ptr(unjittered));
    glUniformMatrix4fv(g.uniform("u_view"), 1, GL_FALSE, glm::value_ptr(current.view));
    glUniformMatrix4fv(g.uniform("u_previous_view_projection"), 1, GL_FALSE,
                       glm::value_ptr(previous_view_projection));
    glUniform2f(g.uniform("u_size"), float(w), float(h));
    glUniform3fv(g.uniform("u_eye"), 1, glm::value_ptr(eye));
    glUniform3fv(g.uniform("u_light_direction"), 1, glm::value_ptr(scene.light.direction));
    glUniform3fv(g.uniform("u_light_color"), 1, glm::value_ptr(scene.light.color));
    glUniform3fv(g.uniform("u_ambient"), 1, glm::value_ptr(scene.light.ambient));
    glUniform1i(g.uniform("u_lit"), settings.shading == Shading::Lit);
    glUniform1i(g.uniform("u_texture"), 0);
    glUniform1f(g.uniform("u_lod_bias"), std::isfinite(settings.texture_lod_bias) ? settings.texture_lod_bias : 0.0f);
    glActiveTexture(GL_TEXTURE0);

    glBindVertexArray(g.vertex_array);
    glBindBuffer(GL_ARRAY_BUFFER, g.vertex_buffer);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(g.vertices.size() * sizeof(Vertex)), g.vertices.data(),
                 GL_STREAM_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.index_buffer);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(g.indices.size() * sizeof(uint32_t)),
                 g.indices.data(), GL_STREAM_DRAW);
    const Material fallback;
    const GLint base_color = g.uniform("u_base_color"), textured = g.uniform("u_textured"),
                specular = g.uniform("u_specular"), shininess = g.uniform("u_shininess"),
                id = g.uniform("u_id");
    for (const Draw& d : g.draws) {
        const Material& m = d.material >= 0 ? scene.materials[d.material] : fallback;
        glUniform4fv(base_color, 1, glm::value_ptr(m.base_color));
        glUniform1i(textured, m.base_color_texture >= 0);
        if (m.base_color_texture >= 0) glBindTexture(GL_TEXTURE_2D, g.textures[m.base_color_texture]);
        glUniform1f(specular, m.specular);
        glUniform1f(shininess, m.shininess);
        glUniform1f(id, d.id);
        if (m.double_sided) glDisable(GL_CULL_FACE);
        else glEnable(GL_CULL_FACE);
        glFrontFace(d.mirrored ? GL_CW : GL_CCW);
        glDrawElements(GL_TRIANGLES, d.index_count, GL_UNSIGNED_INT,
                       (void*)(std::size_t(d.first_index) * sizeof(uint32_t)));
    }

    // Read back, turning GL's bottom-up rows into top-down images.
    if (frame.width() != w || frame.height() != h || frame.depth.empty() || frame.id.empty()) {
        frame.color.resize(w, h);
        frame.depth.resize(w, h);
        frame.motion.resize(w, h);
        frame.normal.resize(w, h);
        frame.id.resize(w, h);
    }
    g.readback.resize(std::size_t(w) * h);
    auto read = [&](int attachment, auto&& store) {
        glReadBuffer(GL_COLOR_ATTACHMENT0 + attachment);
        glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, g.readback.data());
        for (int y = 0; y < h; ++y) {
            const glm::vec4* row = g.readback.data() + std::size_t(h - 1 - y) * w;
            for (int x = 0; x < w; ++x) store(x, y, row[x]);
        }
    };
    read(0, [&](int x, int y, glm::vec4 v) { frame.color(x, y) = v; });
    read(2, [&](int x, int y, glm::vec4 v) { frame.normal(x, y) = glm::vec3(v); });
    // Background: depth +inf, motion of the point at infinity seen through this pixel, with
    // both ends projected the same way (a still camera gives exactly 0).
    // Orthographic cameras see the far plane instead (w = 1: a point, not a direction).
    const double point = current.projection[3][3] == 1.0f ? 1.0 : 0.0;
    const glm::dmat4 unproject = glm::inverse(glm::dmat4(shift * current.projection * current.view));
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
        glm::dvec4 a = unproject * glm::dvec4(ndc, -1.0, 1.0), b = unproject * glm::dvec4(ndc, point, 1.0);
        glm::dvec4 world = point == 1.0 ? b / b.w : glm::dvec4(glm::dvec3(b) / b.w - glm::dvec3(a) / a.w, 0.0);
        glm::dvec2 here, there;
        bool visible = to_pixels(unjittered, world, here) &&
                       to_pixels(previous_view_projection, world, there);
        frame.motion(x, y) = visible ? glm::vec2(there - here) : glm::vec2(nan);
    });
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
    return {};
}

Status Renderer::render_frame(const Scene& scene, const CameraPath& path, int index, double fps,
                              const RenderSettings& settings, Frame& frame) {
    REPRISE_ASSERT(fps > 0);
    const int w = settings.width, h = settings.height;
    Instant now = instant_on_path(path, scene, index / fps, w, h);
    Instant before = instant_on_path(path, scene, (index - 1) / fps, w, h);
    REPRISE_TRY(render(scene, now, before, settings, frame));
    frame.fps = fps;
    return {};
}

Status Renderer::render_frame_lowres(const Scene& scene, const CameraPath& path, int index,
                                     double fps, const RenderSettings& settings, int factor,
                                     Frame& frame, Image<glm::vec4>& low_color, glm::vec2& jitter) {
    REPRISE_ASSERT(fps > 0);
    REPRISE_TRY(check_image_size(settings.width, settings.height, "renderer"));
    const Instant now = instant_on_path(path, scene, index / fps, settings.width, settings.height);
    const Instant before = instant_on_path(path, scene, (index - 1) / fps, settings.width, settings.height);
    REPRISE_TRY(render_lowres(scene, now, before, settings, factor, index, frame, low_color, jitter));
    frame.fps = fps;
    return {};
}

Status Renderer::render_lowres(const Scene& scene, const Instant& current, const Instant& previous,
                               const RenderSettings& settings, int factor, int64_t jitter_index,
                               Frame& frame, Image<glm::vec4>& low_color, glm::vec2& jitter) {
    REPRISE_ASSERT(lowres_factor_valid(factor));
    REPRISE_TRY(check_image_size(settings.width, settings.height, "renderer"));
    REPRISE_TRY(render(scene, current, previous, settings, frame));
    const glm::ivec2 low = lowres_size(settings.width, settings.height, factor);
    // Relative to the unjittered full image (the full frame's own jitter, usually 0, included).
    jitter = current.jitter + lowres_jitter(settings.width, settings.height, factor, jitter_index);
    const glm::vec2 footprint(float(settings.width) / float(low.x), float(settings.height) / float(low.y));
    // The same frustum (projection of the full size) at the low size; the jitter in low pixels.
    Instant now = current;
    now.jitter = jitter / footprint;
    RenderSettings low_settings = settings;
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
    std::copy(scratch.color.data(), scratch.color.data() + scratch.color.pixel_count(), low_color.data());
    return {};
}

}  // namespace reprise::server
