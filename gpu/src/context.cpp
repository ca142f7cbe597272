// The GPU context: its GL context, the counters buffer, and the plumbing of uploads and downloads.
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>

#include "reprise/core/parallel.hpp"
#include "reprise/gpu/context.hpp"
#include "state.hpp"

namespace reprise::gpu {

// One per path, linked once.
Status create_programs(ContextState& state);
Status create_fill_programs(ContextState& state);
Status create_splat_programs(ContextState& state);
Status create_stereo_programs(ContextState& state);
Status create_interpolate_programs(ContextState& state);
Status create_extrapolate_programs(ContextState& state);
Status create_refine_programs(ContextState& state);
Status create_shot_change_program(ContextState& state);
Status create_silhouette_program(ContextState& state);

double ms_since(std::chrono::steady_clock::time_point& since) {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - since).count();
    since = now;
    return ms;
}

double finish_ms(std::chrono::steady_clock::time_point& since) {
    glFinish();
    return ms_since(since);
}

void Texture::ensure(GLenum new_format, int w, int h) {
    if (name && format == new_format && width == w && height == h) return;
    gl::immutable_texture(name, new_format, w, h);
    format = new_format;
    width = w;
    height = h;
}

namespace {

std::size_t texel_bytes(GLenum format) {
    switch (format) {
        case GL_RGBA32F:
            return 16;
        case GL_RGB32F:
            return 12;
        case GL_RG32F:
            return 8;
        case GL_R8UI:
            return 1;
        default:  // GL_R32F, GL_R32UI
            return 4;
    }
}

}  // namespace

void ContextState::bind_inputs(std::initializer_list<GLuint> textures) const {
    REPRISE_ASSERT(textures.size() <= kInputUnits);
    GLuint unit = 0;
    for (GLuint t : textures) {
        glActiveTexture(GL_TEXTURE0 + unit);
        glBindTexture(GL_TEXTURE_2D, t);
        glBindSampler(unit, nearest_sampler);
        ++unit;
    }
    glActiveTexture(GL_TEXTURE0);
}

void ContextState::unbind_inputs() {
    for (GLuint unit = 0; unit < kInputUnits; ++unit) glBindSampler(unit, 0);
}

void ContextState::reset_counters(GLuint buffer, std::size_t count) {
    const GLuint zeros[64] = {};
    REPRISE_ASSERT(count <= 64);
    // After the shader atomics of a pass whose count nobody read back.
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buffer);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(count * sizeof(GLuint)), zeros);
}

void dispatch(int w, int h) {
    glDispatchCompute(GLuint((w + 7) / 8), GLuint((h + 7) / 8), 1);
    // Read-backs put their own barriers (download, read_counters).
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                    GL_SHADER_STORAGE_BARRIER_BIT);
}

void set_view_point(GLuint program, const Unprojector& unproject, int w, int h) {
    glUniformMatrix4fv(glGetUniformLocation(program, "P"), 1, GL_FALSE,
                       &unproject.projection()[0][0]);
    glUniform1f(glGetUniformLocation(program, "background_zv"),
                unproject.perspective() ? -1.0f : -unproject.far_plane());
    glUniform1f(glGetUniformLocation(program, "background_w"),
                unproject.perspective() ? 0.0f : 1.0f);
    glUniform2i(glGetUniformLocation(program, "size"), w, h);
}

Status set_still_test(GLuint program, const Camera& frame, const glm::mat4& view,
                      const glm::mat4& projection, int w, int h, float tolerance) {
    const StaticReprojection to_previous = camera_only_motion(frame, w, h);
    const StaticReprojection to_target(frame, view, projection, w, h);
    if (!to_previous.unprojector().axis_aligned())
        return Status::error("gpu: the frame's projection is skewed");
    set_view_point(program, to_previous.unprojector(), w, h);
    glUniformMatrix4fv(glGetUniformLocation(program, "to_previous"), 1, GL_FALSE,
                       &to_previous.to_clip()[0][0]);
    glUniformMatrix4fv(glGetUniformLocation(program, "to_target"), 1, GL_FALSE,
                       &to_target.to_clip()[0][0]);
    glUniform1f(glGetUniformLocation(program, "tolerance2"), tolerance * tolerance);
    return {};
}

GLuint ContextState::make_counters(std::size_t bytes) {
    GLuint buffer = 0;
    glGenBuffers(1, &buffer);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffer);
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(bytes), nullptr, GL_DYNAMIC_COPY);
    return buffer;
}

void ContextState::read_counters(GLuint buffer, void* counts, std::size_t bytes) {
    REPRISE_ASSERT(bytes <= 64 * sizeof(GLuint));  // the readback buffer's size
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glBindBuffer(GL_COPY_READ_BUFFER, buffer);
    glBindBuffer(GL_COPY_WRITE_BUFFER, readback_buffer);
    glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, 0, 0, GLsizeiptr(bytes));
    std::memset(counts, 0, bytes);
    if (const void* mapped =
            glMapBufferRange(GL_COPY_WRITE_BUFFER, 0, GLsizeiptr(bytes), GL_MAP_READ_BIT)) {
        std::memcpy(counts, mapped, bytes);
        glUnmapBuffer(GL_COPY_WRITE_BUFFER);
    }
    glBindBuffer(GL_COPY_READ_BUFFER, 0);
    glBindBuffer(GL_COPY_WRITE_BUFFER, 0);
}

void ContextState::upload(const Texture& texture, const void* data, std::ptrdiff_t stride,
                          int width, int height) {
    GLenum format = 0, type = 0;
    gl::transfer_format(texture.format, format, type);
    const int w = width > 0 ? width : texture.width, h = height > 0 ? height : texture.height;
    const std::size_t row = texel_bytes(texture.format) * std::size_t(w);
    const std::size_t bytes = row * std::size_t(h);
    const std::size_t source_row = texel_bytes(texture.format) * std::size_t(stride);
    glBindTexture(GL_TEXTURE_2D, texture.name);
    // Tightly packed rows from the start (an adopted context's application may have set these).
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
    glPixelStorei(GL_UNPACK_SKIP_ROWS, 0);
    glPixelStorei(GL_UNPACK_SKIP_PIXELS, 0);
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, unpack_buffer);
    if (bytes > unpack_bytes) {
        glBufferData(GL_PIXEL_UNPACK_BUFFER, GLsizeiptr(bytes), nullptr, GL_STREAM_DRAW);
        unpack_bytes = bytes;
    }
    auto* mapped = static_cast<unsigned char*>(
        glMapBufferRange(GL_PIXEL_UNPACK_BUFFER, 0, GLsizeiptr(bytes),
                         GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT));
    const auto* source = static_cast<const unsigned char*>(data);
    if (!mapped) unpack_bytes = 0;  // allocated again next time (it may have failed)
    if (mapped) {
        parallel_for(0, h, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y)
                std::memcpy(mapped + std::size_t(y) * row, source + std::size_t(y) * source_row,
                            row);
        });
        glUnmapBuffer(GL_PIXEL_UNPACK_BUFFER);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, format, type, nullptr);
        glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
        return;
    }
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);  // the driver would not map: from client memory
    glPixelStorei(GL_UNPACK_ROW_LENGTH, GLint(stride));
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, format, type, data);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
}

Status check_texture(unsigned name, GLenum format, int w, int h, const char* what) {
    // The message is made only on failure: a per-frame call allocates nothing.
    auto where = [&] {
        return std::string("gpu: texture ") + std::to_string(name) + " (" + what + ")";
    };
    if (!name || !glIsTexture(name)) return Status::error(where() + " is not a texture");
    glBindTexture(GL_TEXTURE_2D, name);
    if (glGetError() != GL_NO_ERROR) return Status::error(where() + " is not a 2D texture");
    GLint width = 0, height = 0, internal = 0;
    glGetTexLevelParameteriv(GL_TEXTURE_2D, 0, GL_TEXTURE_WIDTH, &width);
    glGetTexLevelParameteriv(GL_TEXTURE_2D, 0, GL_TEXTURE_HEIGHT, &height);
    glGetTexLevelParameteriv(GL_TEXTURE_2D, 0, GL_TEXTURE_INTERNAL_FORMAT, &internal);
    if (width != w || height != h)
        return Status::error(where() + " is " + std::to_string(width) + "x" +
                             std::to_string(height) + ", expected " + std::to_string(w) + "x" +
                             std::to_string(h));
    if (GLenum(internal) != format) {
        const char* expected = format == GL_RGBA32F  ? "GL_RGBA32F"
                               : format == GL_RGB32F ? "GL_RGB32F"
                               : format == GL_RG32F  ? "GL_RG32F"
                               : format == GL_R32F   ? "GL_R32F"
                               : format == GL_R8UI   ? "GL_R8UI"
                                                     : "GL_R32UI";
        char found[16];
        std::snprintf(found, sizeof found, "0x%04x", unsigned(internal));
        return Status::error(where() + " has internal format " + found + ", expected " + expected);
    }
    return {};
}

void ContextState::upload_frame(const GBufferView& frame, Texture& color_texture,
                                Texture& depth_texture, Texture& motion_texture) {
    const int w = frame.width(), h = frame.height();
    color_texture.ensure(GL_RGBA32F, w, h);
    depth_texture.ensure(GL_R32F, w, h);
    motion_texture.ensure(GL_RG32F, w, h);
    upload(color_texture, frame.color.data, frame.color.stride);
    upload(depth_texture, frame.depth.data, frame.depth.stride);
    upload(motion_texture, frame.motion.data, frame.motion.stride);
}

void ContextState::download(const Texture& texture, void* data, std::ptrdiff_t stride, int width,
                            int height) {
    const int w = width > 0 ? width : texture.width, h = height > 0 ? height : texture.height;
    // Shader image stores become visible to reads through a framebuffer only after this.
    glMemoryBarrier(GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
    glBindFramebuffer(GL_FRAMEBUFFER, read_framebuffer);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture.name, 0);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    if (texture.format == GL_R32UI) {
        hit_readback.resize(std::size_t(w) * std::size_t(h));
        glReadPixels(0, 0, w, h, GL_RGBA_INTEGER, GL_UNSIGNED_INT, hit_readback.data());
    } else {
        glPixelStorei(GL_PACK_ROW_LENGTH, GLint(stride));
        glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, data);
        glPixelStorei(GL_PACK_ROW_LENGTH, 0);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void ContextState::download_channels(const Texture& texture, float* data, int channels,
                                     std::ptrdiff_t stride) {
    const int w = texture.width, h = texture.height;
    float_readback.resize(std::size_t(w) * std::size_t(h));
    download(texture, float_readback.data(), w);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < channels; ++c)
                data[(std::size_t(y) * std::size_t(stride) + std::size_t(x)) *
                         std::size_t(channels) +
                     std::size_t(c)] = float_readback[std::size_t(y) * w + x][c];
}

void ContextState::download_made(Frame& made) {
    const int w = color.width, h = color.height;
    made.color.resize(w, h);
    made.depth.resize(w, h);
    download(color, made.color.data(), w);
    download_channels(depth, made.depth.data(), 1, w);
}

Context::Context() : state_(std::make_unique<ContextState>()) {}

Context::~Context() {
    // An adopted context that is not current here: its objects cannot be reached (left to it).
    if (!state_->gl || !state_->gl->acquire().ok()) return;
    for (Texture* t : {&state_->depth,
                       &state_->motion,
                       &state_->id,
                       &state_->previous_depth,
                       &state_->previous_id,
                       &state_->payload,
                       &state_->out,
                       &state_->hit,
                       &state_->color,
                       &state_->valid,
                       &state_->splat_motion,
                       &state_->displacement,
                       &state_->target_depth,
                       &state_->eye_color,
                       &state_->source_color,
                       &state_->source_depth,
                       &state_->source_motion,
                       &state_->made_motion,
                       &state_->history_color,
                       &state_->history_depth,
                       &state_->history_motion,
                       &state_->history_displacement,
                       &state_->history_target_depth,
                       &state_->history_warped,
                       &state_->history_warped_depth,
                       &state_->history_covered,
                       &state_->merged,
                       &state_->eye_wide_depth,
                       &state_->history_wide_depth,
                       &state_->history_wide_motion,
                       &state_->source_wide_depth,
                       &state_->source_wide_motion,
                       &state_->display_table,
                       &state_->shot_reprojected,
                       &state_->shot_hit})
        glDeleteTextures(1, &t->name);
    for (Texture* t : state_->interpolation.all) glDeleteTextures(1, &t->name);
    for (Texture* t : state_->refinement.all) glDeleteTextures(1, &t->name);
    for (GLuint program : state_->refine_programs) glDeleteProgram(program);
    glDeleteBuffers(1, &state_->refinement.won);
    glDeleteProgram(state_->border_program);
    glDeleteBuffers(1, &state_->border_counts);
    glDeleteProgram(state_->widen_program);
    glDeleteBuffers(1, &state_->widen_counts);
    for (auto* chain :
         {&state_->pulled, &state_->pulled_depth, &state_->filled, &state_->filled_depth})
        for (Texture& t : *chain) glDeleteTextures(1, &t.name);
    for (GLuint program :
         {state_->pull_image_program,   state_->pull_level_program,    state_->push_program,
          state_->final_program,        state_->splat_scatter_program, state_->splat_clear_program,
          state_->splat_gather_program, state_->displacement_program,  state_->finish_program,
          state_->blend_program,        state_->copy_program,          state_->static_layer_program,
          state_->merge_program,        state_->refetch_program,       state_->true_motion_program,
          state_->survey_program,       state_->invert_programs[0],    state_->invert_programs[1],
          state_->invert_programs[2],   state_->invert_programs[3],    state_->shot_change_program})
        glDeleteProgram(program);
    for (GLuint buffer : {state_->blend_counts, state_->extrapolate_counts, state_->eye_counts,
                          state_->invert_buffer, state_->shot_change_counts})
        glDeleteBuffers(1, &buffer);
    glDeleteBuffers(1, &state_->splat_counts);
    glDeleteBuffers(1, &state_->splat_lists);
    glDeleteBuffers(1, &state_->fill_counts);
    glDeleteBuffers(1, &state_->small_levels);
    glDeleteProgram(state_->small_levels_program);
    glDeleteSamplers(1, &state_->nearest_sampler);
    glDeleteBuffers(1, &state_->counts_buffer);
    glDeleteBuffers(1, &state_->unpack_buffer);
    glDeleteBuffers(1, &state_->readback_buffer);
    glDeleteFramebuffers(1, &state_->read_framebuffer);
    glDeleteProgram(state_->reproject_program);
    destroy_grid(state_->grid);
}

Status Context::create(std::unique_ptr<Context>& context) {
    std::unique_ptr<gl::Context> gl;
    REPRISE_TRY(gl::Context::create(gl));
    return create_on(std::move(gl), context);
}

Status Context::adopt_current(std::unique_ptr<Context>& context) {
    std::unique_ptr<gl::Context> gl;
    REPRISE_TRY(gl::Context::adopt_current(gl));
    return create_on(std::move(gl), context);
}

Status Context::create_on(std::unique_ptr<gl::Context> gl, std::unique_ptr<Context>& context) {
    std::unique_ptr<Context> made(new Context());
    ContextState& s = *made->state_;
    s.gl = std::move(gl);
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major < 3 || (major == 3 && minor < 1))
        return Status::error("gpu: OpenGL ES 3.1 (compute shaders) is needed; " +
                             s.gl->description() + " has " + std::to_string(major) + "." +
                             std::to_string(minor));
    // The passes write up to 5 images in one dispatch (the upsampler's history pass) at units up
    // to 6 (the splat's gather); GL ES 3.1 promises 4 of each.
    GLint images = 0, units = 0;
    glGetIntegerv(GL_MAX_COMPUTE_IMAGE_UNIFORMS, &images);
    glGetIntegerv(GL_MAX_IMAGE_UNITS, &units);
    if (images < 5 || units < 7)
        return Status::error("gpu: " + s.gl->description() + " offers " + std::to_string(images) +
                             " compute image uniforms and " + std::to_string(units) +
                             " image units; the GPU paths need 5 and 7");
    REPRISE_TRY(create_programs(s));
    REPRISE_TRY(create_fill_programs(s));
    REPRISE_TRY(create_splat_programs(s));
    REPRISE_TRY(create_stereo_programs(s));
    REPRISE_TRY(create_interpolate_programs(s));
    REPRISE_TRY(create_extrapolate_programs(s));
    REPRISE_TRY(create_refine_programs(s));
    REPRISE_TRY(create_silhouette_program(s));
    s.counts_buffer = s.make_counters(8 * sizeof(GLuint));
    glGenBuffers(1, &s.readback_buffer);
    glBindBuffer(GL_COPY_WRITE_BUFFER, s.readback_buffer);
    glBufferData(GL_COPY_WRITE_BUFFER, 64 * sizeof(GLuint), nullptr, GL_STREAM_READ);
    glGenFramebuffers(1, &s.read_framebuffer);
    glGenBuffers(1, &s.unpack_buffer);
    glGenSamplers(1, &s.nearest_sampler);
    glSamplerParameteri(s.nearest_sampler, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glSamplerParameteri(s.nearest_sampler, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    REPRISE_TRY(create_shot_change_program(s));  // uploads its table: after the unpack buffer
    REPRISE_TRY(gl::check_errors("gpu context"));
    context = std::move(made);
    return {};
}

void Context::make_current() const { state_->gl->make_current(); }

const std::string& Context::description() const { return state_->gl->description(); }

}  // namespace reprise::gpu
