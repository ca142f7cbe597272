#pragma once
// The headless G-buffer renderer: colour, linear depth, exact backward motion, world normals and
// object ids of a Scene, through OpenGL ES 3 on EGL.
#include <memory>
#include <string>

#include "reprise/core/frame.hpp"
#include "reprise/server/camera_path.hpp"
#include "reprise/server/scene.hpp"

namespace reprise::server {

enum class Shading {
    Lit,    // base colour x (ambient + directional diffuse) + Blinn-Phong specular
    Unlit,  // base colour only: view-independent, for checking motion against colour
};

struct RenderSettings {
    int width = 640;
    int height = 360;
    Shading shading = Shading::Lit;
};

// The camera and the animation timeline at one instant.
struct Instant {
    double time = 0.0;
    glm::mat4 view{1.0f};
    glm::mat4 projection{1.0f};  // without jitter
    glm::vec2 jitter{0.0f};      // pixel p samples the unjittered image at p + jitter
    float near = 0.1f;
    float far = 1000.0f;
};

Instant instant_on_path(const CameraPath& path, const Scene& scene, double time, int width,
                        int height);

class Renderer {
public:
    static Status create(std::unique_ptr<Renderer>& renderer);
    ~Renderer();

    // Renders `current`; motion points to where each surface point was at `previous`
    // (camera, node animation, skin and morph). Buffers of `frame` are resized as needed.
    Status render(const Scene& scene, const Instant& current, const Instant& previous,
                  const RenderSettings& settings, Frame& frame);

    // Frame `index` of a sequence at `fps` on the scene's timeline (time = index / fps); the
    // previous instant is one frame period earlier, so frame 0 has motion too.
    Status render_frame(const Scene& scene, const CameraPath& path, int index, double fps,
                        const RenderSettings& settings, Frame& frame);

    const std::string& device() const;

private:
    Renderer();
    struct Gpu;
    std::unique_ptr<Gpu> gpu_;
};

}  // namespace reprise::server
