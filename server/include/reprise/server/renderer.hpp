#pragma once
// The headless G-buffer renderer: colour, linear depth, exact backward motion, world normals and
// object ids of a Scene, through OpenGL ES 3 on EGL.
#include <cstdint>
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
    float texture_lod_bias = 0.0f;  // added to the texture level of detail (negative: sharper)
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

// Low-resolution jittered colour (Pajak et al. 2011, Herzog et al. 2010): `factor` 2 renders ½ of
// the pixels (ceil(W/2) x H), 4 renders ¼ (ceil(W/2) x ceil(H/2)), 1 all of them. The low image
// covers the same frustum; its jitter (in full-resolution pixels) cycles through the centres of
// the full pixels under one low pixel: 2x1 as (-0.5, 0), (+0.5, 0); 2x2 as (-0.5, -0.5),
// (+0.5, +0.5), (+0.5, -0.5), (-0.5, +0.5), so every full pixel is sampled once per cycle.
// (Sizes that do not divide give proportionally placed samples instead of exact centres.)
bool lowres_factor_valid(int factor);
glm::ivec2 lowres_size(int width, int height, int factor);
glm::vec2 lowres_jitter(int width, int height, int factor, int64_t index);

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

    // Frame `index` as render_frame() at full resolution, unjittered, plus its colour at 1/factor of
    // the pixels with lowres_jitter(index) into `low_color` (texture level of detail biased
    // towards the full resolution's, so low samples about equal full-resolution ones). `jitter`
    // receives the jitter used, in full-resolution pixels.
    Status render_frame_lowres(const Scene& scene, const CameraPath& path, int index, double fps,
                               const RenderSettings& settings, int factor, Frame& frame,
                               Image<glm::vec4>& low_color, glm::vec2& jitter);
    // The same from explicit instants (a streaming session's poses): `current` and `previous`
    // without jitter, their projections made for the full size; `jitter_index` picks
    // lowres_jitter's phase (a frame counter).
    Status render_lowres(const Scene& scene, const Instant& current, const Instant& previous,
                         const RenderSettings& settings, int factor, int64_t jitter_index,
                         Frame& frame, Image<glm::vec4>& low_color, glm::vec2& jitter);

    const std::string& device() const;

private:
    Renderer();
    struct Gpu;
    std::unique_ptr<Gpu> gpu_;
};

}  // namespace reprise::server
