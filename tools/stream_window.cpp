#include "stream_window.hpp"

#include <SDL.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <vector>

#include "reprise/core/visualize.hpp"
#include "reprise/gl/program.hpp"

namespace reprise::cli {

namespace {

// A full-window triangle; each fragment takes the texel under it (nearest, row 0 at the top)
// and shows its display value as visualize_color computes it.
constexpr const char* kVertex = R"(#version 310 es
void main() {
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    gl_Position = vec4(p, 0.0, 1.0);
}
)";
constexpr const char* kFragment = R"(#version 310 es
precision highp float;
uniform highp sampler2D colour;
uniform vec2 window_size;
out vec4 shown;
float display(float c) {
    if ((floatBitsToUint(c) & 0x7fffffffu) > 0x7f800000u) return 0.0;  // NaN
    c = clamp(c, 0.0, 1.0);
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}
void main() {
    ivec2 size = textureSize(colour, 0);
    vec2 at = vec2(gl_FragCoord.x, window_size.y - gl_FragCoord.y) / window_size;
    ivec2 texel = min(ivec2(at * vec2(size)), size - 1);
    vec3 c = texelFetch(colour, texel, 0).rgb;
    shown = vec4(display(c.r), display(c.g), display(c.b), 1.0);
}
)";

}  // namespace

struct StreamWindow::State {
    SDL_Window* window = nullptr;
    SDL_Renderer* renderer = nullptr;
    SDL_Texture* texture = nullptr;
    SDL_GLContext gl = nullptr;
    GLuint program = 0, uploaded = 0;  // GlEs: the drawing program, CPU frames' texture
    int tw = 0, th = 0;
    bool interactive = false;
    glm::vec3 position{0.0f};
    float yaw = 0.0f, pitch = 0.0f;
    Image<Rgb8> pixels;

    ~State() {
        if (gl) {
            SDL_GL_MakeCurrent(window, gl);
            if (program) glDeleteProgram(program);
            if (uploaded) glDeleteTextures(1, &uploaded);
            SDL_GL_DeleteContext(gl);
        }
        if (texture) SDL_DestroyTexture(texture);
        if (renderer) SDL_DestroyRenderer(renderer);
        if (window) SDL_DestroyWindow(window);
        SDL_QuitSubSystem(SDL_INIT_VIDEO);
    }
    glm::mat4 camera_to_world() const {
        glm::mat4 m = glm::translate(glm::mat4(1.0f), position);
        m = glm::rotate(m, yaw, glm::vec3(0, 1, 0));
        return glm::rotate(m, pitch, glm::vec3(1, 0, 0));
    }
    Status open_gl() {
        gl = SDL_GL_CreateContext(window);
        if (!gl) return Status::error(std::string("SDL2 OpenGL ES 3.1 context: ") + SDL_GetError());
        if (SDL_GL_MakeCurrent(window, gl) != 0)
            return Status::error(std::string("SDL2 OpenGL ES context: ") + SDL_GetError());
        SDL_GL_SetSwapInterval(0);  // the display loop keeps its own time
        REPRISE_TRY(gl::link_program(kVertex, kFragment, "window", program));
        glGenTextures(1, &uploaded);
        return gl::check_errors("window");
    }
    // Draws `texture` (GL_RGBA32F, linear colour) over the window and presents it.
    Status draw(GLuint colour) {
        int w = 0, h = 0;
        SDL_GL_GetDrawableSize(window, &w, &h);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glViewport(0, 0, w, h);
        glUseProgram(program);
        glUniform2f(glGetUniformLocation(program, "window_size"), float(w), float(h));
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, colour);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glBindTexture(GL_TEXTURE_2D, 0);
        glUseProgram(0);
        SDL_GL_SwapWindow(window);
        return gl::check_errors("window");
    }
};

StreamWindow::StreamWindow() : state_(std::make_unique<State>()) {}
StreamWindow::~StreamWindow() = default;

Status StreamWindow::open(bool interactive, const glm::mat4& start_view, Drawing drawing,
                          std::unique_ptr<StreamWindow>& window) {
    if (SDL_InitSubSystem(SDL_INIT_VIDEO) != 0)
        return Status::error(std::string("SDL2: ") + SDL_GetError());
    std::unique_ptr<StreamWindow> w(new StreamWindow());
    State& s = *w->state_;
    const bool gles = drawing == Drawing::GlEs;
    if (gles) {  // an EGL context (the GPU adopts it), also under X11, where SDL prefers GLX
        SDL_SetHint(SDL_HINT_VIDEO_X11_FORCE_EGL, "1");
        SDL_GL_SetAttribute(SDL_GL_CONTEXT_PROFILE_MASK, SDL_GL_CONTEXT_PROFILE_ES);
        SDL_GL_SetAttribute(SDL_GL_CONTEXT_MAJOR_VERSION, 3);
        SDL_GL_SetAttribute(SDL_GL_CONTEXT_MINOR_VERSION, 1);
    }
    s.window = SDL_CreateWindow("reprise connect", SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED,
                                960, 540, SDL_WINDOW_RESIZABLE | (gles ? SDL_WINDOW_OPENGL : 0));
    if (!s.window) return Status::error(std::string("SDL2 window: ") + SDL_GetError());
    if (gles) {
        REPRISE_TRY(s.open_gl());
    } else {
        s.renderer = SDL_CreateRenderer(
            s.window, -1, drawing == Drawing::SdlSoftware ? SDL_RENDERER_SOFTWARE : 0);
        if (!s.renderer) return Status::error(std::string("SDL2 renderer: ") + SDL_GetError());
    }
    s.interactive = interactive;
    // The free camera starts where the path's camera is: position and heading of its inverse.
    const glm::mat4 to_world = glm::inverse(start_view);
    s.position = glm::vec3(to_world[3]);
    const glm::vec3 forward = -glm::vec3(to_world[2]);
    s.yaw = std::atan2(-forward.x, -forward.z);
    s.pitch = std::asin(std::clamp(forward.y, -1.0f, 1.0f));
    window = std::move(w);
    return {};
}

bool StreamWindow::pump(double dt) {
    State& s = *state_;
    SDL_Event e;
    while (SDL_PollEvent(&e)) {
        if (e.type == SDL_QUIT) return false;
        if (e.type == SDL_KEYDOWN && e.key.keysym.sym == SDLK_ESCAPE) return false;
        if (s.interactive && e.type == SDL_MOUSEMOTION && (e.motion.state & SDL_BUTTON_LMASK)) {
            s.yaw -= 0.005f * float(e.motion.xrel);
            s.pitch = std::clamp(s.pitch - 0.005f * float(e.motion.yrel), -1.5f, 1.5f);
        }
    }
    if (!s.interactive) return true;
    const Uint8* keys = SDL_GetKeyboardState(nullptr);
    const glm::mat4 m = s.camera_to_world();
    const glm::vec3 right(m[0]), up(0, 1, 0), back(m[2]);
    const float step = float(2.0 * dt), turn = float(1.2 * dt);
    if (keys[SDL_SCANCODE_W]) s.position -= back * step;
    if (keys[SDL_SCANCODE_S]) s.position += back * step;
    if (keys[SDL_SCANCODE_D]) s.position += right * step;
    if (keys[SDL_SCANCODE_A]) s.position -= right * step;
    if (keys[SDL_SCANCODE_E]) s.position += up * step;
    if (keys[SDL_SCANCODE_Q]) s.position -= up * step;
    if (keys[SDL_SCANCODE_LEFT]) s.yaw += turn;
    if (keys[SDL_SCANCODE_RIGHT]) s.yaw -= turn;
    if (keys[SDL_SCANCODE_UP]) s.pitch = std::min(1.5f, s.pitch + turn);
    if (keys[SDL_SCANCODE_DOWN]) s.pitch = std::max(-1.5f, s.pitch - turn);
    return true;
}

glm::mat4 StreamWindow::view() const { return glm::inverse(state_->camera_to_world()); }

bool StreamWindow::draws_textures() const { return state_->gl != nullptr; }

Status StreamWindow::show(const GBufferView& frame) {
    State& s = *state_;
    const int w = frame.width(), h = frame.height();
    if (w <= 0 || h <= 0) return {};
    if (s.gl) {
        glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
        if (s.tw != w || s.th != h) {
            gl::allocate_texture(s.uploaded, GL_RGBA32F, w, h);
            s.tw = w, s.th = h;
        }
        glBindTexture(GL_TEXTURE_2D, s.uploaded);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        glPixelStorei(GL_UNPACK_ROW_LENGTH, int(frame.color.stride));
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, frame.color.data);
        glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
        glBindTexture(GL_TEXTURE_2D, 0);
        return s.draw(s.uploaded);
    }
    if (!s.texture || s.tw != w || s.th != h) {
        if (s.texture) SDL_DestroyTexture(s.texture);
        s.texture =
            SDL_CreateTexture(s.renderer, SDL_PIXELFORMAT_RGB24, SDL_TEXTUREACCESS_STREAMING, w, h);
        s.tw = w, s.th = h;
        s.pixels = Image<Rgb8>(w, h);
    }
    if (!s.texture) return Status::error(std::string("SDL2 texture: ") + SDL_GetError());
    visualize_color(frame.color, s.pixels.view());
    SDL_UpdateTexture(s.texture, nullptr, s.pixels.data(),
                      int(s.pixels.view().stride * sizeof(Rgb8)));
    SDL_RenderClear(s.renderer);
    SDL_RenderCopy(s.renderer, s.texture, nullptr, nullptr);
    SDL_RenderPresent(s.renderer);
    return {};
}

Status StreamWindow::show(const gpu::MadeTextures& frame) {
    State& s = *state_;
    if (!s.gl) return Status::error("window: textures are drawn only in an OpenGL ES window");
    if (!frame.color || frame.width <= 0 || frame.height <= 0)
        return Status::error("window: no texture to draw");
    return s.draw(frame.color);
}

}  // namespace reprise::cli
