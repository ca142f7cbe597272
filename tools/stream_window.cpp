#include "stream_window.hpp"

#include <SDL.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <vector>

#include "reprise/core/visualize.hpp"

namespace reprise::cli {

struct StreamWindow::State {
    SDL_Window* window = nullptr;
    SDL_Renderer* renderer = nullptr;
    SDL_Texture* texture = nullptr;
    int tw = 0, th = 0;
    bool interactive = false;
    glm::vec3 position{0.0f};
    float yaw = 0.0f, pitch = 0.0f;
    Image<Rgb8> pixels;

    ~State() {
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
};

StreamWindow::StreamWindow() : state_(std::make_unique<State>()) {}
StreamWindow::~StreamWindow() = default;

Status StreamWindow::open(bool interactive, const glm::mat4& start_view, bool software,
                          std::unique_ptr<StreamWindow>& window) {
    if (SDL_InitSubSystem(SDL_INIT_VIDEO) != 0)
        return Status::error(std::string("SDL2: ") + SDL_GetError());
    std::unique_ptr<StreamWindow> w(new StreamWindow());
    State& s = *w->state_;
    s.window = SDL_CreateWindow("reprise connect", SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED,
                                960, 540, SDL_WINDOW_RESIZABLE);
    if (!s.window) return Status::error(std::string("SDL2 window: ") + SDL_GetError());
    s.renderer = SDL_CreateRenderer(s.window, -1, software ? SDL_RENDERER_SOFTWARE : 0);
    if (!s.renderer) return Status::error(std::string("SDL2 renderer: ") + SDL_GetError());
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

void StreamWindow::show(const GBufferView& frame) {
    State& s = *state_;
    const int w = frame.width(), h = frame.height();
    if (!s.texture || s.tw != w || s.th != h) {
        if (s.texture) SDL_DestroyTexture(s.texture);
        s.texture =
            SDL_CreateTexture(s.renderer, SDL_PIXELFORMAT_RGB24, SDL_TEXTUREACCESS_STREAMING, w, h);
        s.tw = w, s.th = h;
        s.pixels = Image<Rgb8>(w, h);
    }
    if (!s.texture) return;
    visualize_color(frame.color, s.pixels.view());
    SDL_UpdateTexture(s.texture, nullptr, s.pixels.data(),
                      int(s.pixels.view().stride * sizeof(Rgb8)));
    SDL_RenderClear(s.renderer);
    SDL_RenderCopy(s.renderer, s.texture, nullptr, nullptr);
    SDL_RenderPresent(s.renderer);
}

}  // namespace reprise::cli
