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
    // Procedural albedo (octaves of value noise), the key light's shadow map filtered by wide
    // PCF, the scene's point lights: shading dominates the frame. The only mode with reuse.
    Heavy,
};

// Shading reuse of the heavy mode (Nehab et al. 2007, Mueller et al. 2021): the expensive, slowly
// varying term (albedo and key-light visibility) is cached in screen space and reused through
// reverse reprojection; the view-dependent rest (lights, highlights) is computed every frame.
enum class Reuse {
    Off,       // full shading everywhere, the cache is neither read nor written
    Cache,     // reuse on a cache hit unless the refresh pattern or the period says reshade
    Adaptive,  // reuse until the predicted change (temporal gradient x age) reaches threshold
};

// Where the forced refreshes of Reuse::Cache fall; each pixel's phase d refreshes it when
// (frame + d) mod period == 0.
enum class Refresh {
    Tiled,        // the screen in `period` tiles, one refreshed per frame
    Random,       // random phase per 2x2 block
    Blocks,       // random phase per 8x8 block (coarse enough for lock-step SIMD shading)
    Interleaved,  // phase (x + k y) mod period: refreshed pixels spread evenly
};

struct ReuseSettings {
    Reuse mode = Reuse::Off;
    Refresh refresh = Refresh::Blocks;
    int period = 4;  // every covered pixel is reshaded at least this often (1..255)
    float threshold = 8.0f / 255.0f;  // Adaptive: allowed change per display channel
    int filter_radius = 1;            // Adaptive: spatial max filter of gradients, (2r+1)^2 (0..3)
    // Hit test: bilinear depth within this many steps of a 24-bit Z-buffer (Nehab's ε is one
    // step; faceted curved surfaces need room).
    float depth_epsilon = 1024.0f;
    // Amortized supersampling of the key light's shadow (Nehab §6): on a hit, a few jittered
    // PCF taps are blended into the cached visibility with this weight; 0 = off.
    float smoothing = 0.0f;
};

enum class AntiAliasing { Auto, Msaa, Supersampling };

struct RenderSettings {
    int width = 640;
    int height = 360;
    Shading shading = Shading::Lit;
    ReuseSettings reuse;
    int heavy_octaves = 8;          // per noise layer (three layers)
    int heavy_pcf_radius = 5;       // (2r+1)^2 shadow-map comparisons
    float texture_lod_bias = 0.0f;  // added to the texture level of detail (negative: sharper)
    // Anti-aliased colour: samples per pixel, 1 (off), 2, 4, 8 or 16, around the jittered pixel
    // centre. MSAA where the device has the count for float targets, else supersampling (one
    // jittered colour pass per sample). Depth, motion, normal, id and colour's A (coverage) stay
    // single samples at the pixel centre. Heavy shading and render_lowres() (both its images:
    // the upsampler rebuilds the point-sampled full image) are single-sample whatever this says.
    int aa_samples = 4;
    // Auto: MSAA on hardware, supersampling on software rasterisers (llvmpipe's 4x MSAA took
    // 29 s where supersampling took 1 s for four 192x108 frames of `cut`'s second shot).
    AntiAliasing aa_method = AntiAliasing::Auto;
};

bool aa_samples_valid(int samples);

// What rendering at these settings holds, estimated before anything is allocated (bytes a
// pixel): the float G-buffer, three RGBA32F targets and depth-stencil (56), the read-back rows
// (16) and the Frame (44); MSAA adds samples x 20, heavy shading its cache (50); a low-resolution
// pass (lowres_factor 2 or 4) a second Frame and its colour at 1/factor of the pixels.
std::uint64_t render_memory(const RenderSettings& settings, bool msaa, int lowres_factor = 1);

// What reuse did in the last frame rendered with Shading::Heavy.
struct ReuseStats {
    int64_t covered = 0;  // pixels with geometry
    int64_t hits = 0;     // covered pixels whose reprojection passed the depth and id test
    int64_t reused = 0;   // hits that reused the cache (not reshaded)
    int64_t shaded = 0;   // covered pixels that ran the expensive term
    double shading_ms =
        0;  // depth pre-pass and shading passes to glFinish (no shadow map, no read-back)
    double shading_cpu_ms = 0;  // the same pass in CPU time of the whole process (software GL)
    double hit_rate() const { return covered ? double(hits) / double(covered) : 0.0; }
    double shaded_fraction() const { return covered ? double(shaded) / double(covered) : 0.0; }
};

// Per pixel of the last heavy frame: kReuseBackground, kReuseMiss, kReuseHit (reused) or
// kReuseRefresh (a hit reshaded by the policy), and frames since the pixel's expensive term was
// last computed (0 = this frame).
inline constexpr uint8_t kReuseBackground = 0, kReuseMiss = 1, kReuseHit = 2, kReuseRefresh = 3;
struct ReuseMaps {
    Image<uint8_t> status;
    Image<uint8_t> age;
};

const char* to_string(Refresh refresh);
// "tiled:4", "random:8", "blocks:4", "interleaved:2"
Status parse_refresh(const std::string& spec, ReuseSettings& reuse);

// The camera and the animation timeline at one instant.
struct Instant {
    double time = 0.0;
    glm::mat4 view{1.0f};
    glm::mat4 projection{1.0f};  // without jitter
    glm::vec2 jitter{0.0f};      // pixel p samples the unjittered image at p + jitter
    float near = 0.1f;
    float far = 1000.0f;
    bool cut = false;  // a camera cut lies between `previous` and this instant: nothing is reused
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
// Whether the path cuts between the two instants (Instant::cut).
bool cut_between(const CameraPath& path, const Instant& before, const Instant& now);

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

    // Frame `index` as render_frame() at full resolution, unjittered, plus its colour at 1/factor
    // of the pixels with lowres_jitter(index) into `low_color` (texture level of detail biased
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

    // Refuses, before anything is allocated, a size beyond this device's largest render target
    // or texture, or render_memory() beyond the memory limit (reprise/core/memory_limit.hpp).
    // Every render checks its own pass; call it first to refuse before other work.
    Status check_settings(const RenderSettings& settings, int lowres_factor = 1) const;

    const std::string& device() const;
    // True when `samples` of anti-aliasing run as MSAA here (with AntiAliasing::Auto), false
    // when as supersampling.
    bool msaa_supported(int samples) const;

    // Reuse of the last heavy frame. The cache survives between frames of one sequence; it is
    // dropped at a cut, a size change, or when `previous` is not the instant rendered last.
    const ReuseStats& reuse_stats() const;
    const ReuseMaps& reuse_maps() const;
    void drop_reuse_cache();

private:
    Renderer();
    struct Gpu;
    std::unique_ptr<Gpu> gpu_;
};

}  // namespace reprise::server
