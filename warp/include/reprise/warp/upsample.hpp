#pragma once
// Spatio-temporal upsampling (Herzog, Eisemann, Myszkowski and Seidel 2010): colour rendered at a
// fraction of the pixels with a per-frame sub-pixel jitter becomes a full-resolution image, guided
// by the full-resolution G-buffer of the same frame (depth, normals, ids, motion).
//
// Geometry of the low-resolution colour: any size lw x lh (1 <= lw <= W, 1 <= lh <= H) covering
// the same frustum as the full image, so each low pixel spans s = (W / lw, H / lh) full pixels;
// reprise renders ½ of the pixels as ceil(W/2) x H and ¼ as ceil(W/2) x ceil(H/2). Low pixel
// (u, v) holds the scene sampled at the full-resolution position
//     ((u + 0.5) * s.x + jitter.x, (v + 0.5) * s.y + jitter.y)
// (the renderer's convention: a pixel samples the unjittered image at its centre + jitter, with
// the jitter given in full-resolution pixels). A full G-buffer with its own jitter
// (full.camera.jitter, 0 as reprise renders it) is accounted for the same way. With a jitter cycle
// that visits every full pixel centre of a low pixel's footprint (server::lowres_jitter), a still
// scene converges.
//
// Per pixel i (equations of the paper):
//   w_s(i, j) = g(max(0, 1 - n_i.n_j)^2, sigma_n^2, 3) * g(dz^2, sigma_d^2, 3) * k(i, j)   (2)
//   g(x, sigma, gamma) = max(eps, 1 - x / sigma)^gamma                                      (3)
//   k(i, j) = g(|x_i - x_j|, r, gamma_k), r = the low-resolution pixel diagonal (by default a
//             separable tent over one low pixel per axis instead, see separable_filter)
//   spatial:  h~ = sum w_s l(j) / sum w_s over the 2x2 nearest low samples                  (6)
//   temporal: h = (h~ w~ + w_f h_w h_r) / (w~ + w_f h_w), h_w' = w~ + w_f h_w  (history at
//             p + motion, bilinear, taps rejected by depth and id)                          (7)
//   steering: w_f = a (1 - |grad|)^2, gamma_k = gamma_max * w_f, where |grad| is the relative
//             luminance difference to the history, filtered over 4 frames (0.4, 0.3, 0.2, 0.1)
//             and over space (a box slightly larger than a low pixel); 1 where disoccluded. (8)
// Deviation: the depth sigma is relative to the pixel's own depth (the paper's 3 % of far - near
// needs a finite far plane; reprise's cameras often have none).
#include <cstdint>

#include "reprise/core/gbuffer.hpp"
#include "reprise/core/image.hpp"
#include "reprise/core/nonfinite.hpp"
#include "reprise/core/status.hpp"

namespace reprise::warp {

struct UpsampleOptions {
    float history_weight = 1.0f;       // a of eq. 8 (the paper uses 1; 0.7 favours spatial)
    float fixed_falloff = 0.9f;        // w_f when gradient steering is off (the paper's 0.9^q)
    float max_history_weight = 16.0f;  // cap on h_w, in units of one perfectly matching sample
    float normal_sigma = 0.2f;         // sigma_n of eq. 2
    float depth_sigma = 0.03f;         // sigma_d as a fraction of the pixel's depth
    float gamma_max = 4.0f;            // largest fall-off of the image-space filter k
    float gamma_unsteered = 3.0f;   // fall-off of k without steering and for the gradient estimate
    float gamma_min = 1.0f;         // floor of the steered fall-off (1: a hat, as plain joint
                                    // bilateral upsampling; the paper's 0 is a box)
    float epsilon = 0.01f;          // weight floor of g (eq. 3)
    bool gradient_steering = true;  // temporal gradients steer w_f and gamma_k (section 3.5)
    bool id_test = true;            // history and spatial samples must carry the pixel's id
    // Relative depth difference that still counts as the same surface (x4 where ids match).
    float history_depth_tolerance = 0.05f;
    int gradient_radius = 0;     // box radius of the gradient low-pass; 0 = one low pixel + 1
    float gradient_gain = 1.0f;  // |grad| is multiplied by this before eq. 8 (the paper: 1)
    // Beyond the paper: < 0 leaves the history as it is; >= 0 clamps it to the colour box of this
    // frame's 2x2 samples on the same surface, widened by this fraction of the box's size on each
    // side (as temporal anti-aliasing does), so changed shading cannot linger.
    float history_clamp = 0.25f;
    // Recompute the spatial taps in the final pass instead of reusing the gradient pass's (the
    // reference the tests compare the cached path with; the results are identical).
    bool recompute_taps = false;
    // Beyond the paper: k as a separable tent over one low pixel per axis (gamma_k = 1: bilinear
    // weights); false: the paper's radial fall-off over the low pixel's diagonal, which blurs
    // across the full-resolution rows of ½-pixel colour (measured +0.3..0.8 dB at ¼, +1..1.4 dB at
    // ½).
    bool separable_filter = true;
};

// Counts of one upsample() call (overwritten by each call).
struct UpsampleStats {
    int64_t history_rejected = 0;  // pixels whose history existed but was disoccluded or off-screen
    int64_t history_used = 0;      // pixels blended with their history
    int64_t nonfinite_samples = 0;  // low-resolution sample reads skipped for NaN/Inf colour
    int64_t unresolved = 0;         // pixels with neither a finite sample nor history (written 0)
    // Non-finite values in: the low-resolution colour (pixels; invalid samples, skipped as above)
    // and the guides (depth NaN/-inf, motion, normals: unknown, repaired before use).
    NonfiniteCounts nonfinite;
};

// Upsampling elsewhere than on the CPU (a GPU: gpu::Upsampler) with SpatioTemporalUpsampler's
// inputs, output and history; an error (the device went away, an input it cannot take) says why.
class UpsampleBackend {
public:
    virtual ~UpsampleBackend() = default;
    virtual Status upsample(ImageView<const glm::vec4> low_color, glm::vec2 jitter_px,
                            const GBufferView& full, ImageView<glm::vec4> out,
                            UpsampleStats* stats = nullptr) = 0;
    virtual void reset() = 0;
    // Whether the last successful upsample() left `out` unwritten and kept its result on the
    // backend's device (for a warp backend there: gpu::Upsampler::keep_output); download_kept()
    // then writes it into `out` for a reader on the CPU.
    virtual bool output_kept() const { return false; }
    virtual Status download_kept(ImageView<glm::vec4> /*out*/) {
        return Status::error("upsample: this backend keeps no output");
    }
};

class SpatioTemporalUpsampler {
public:
    explicit SpatioTemporalUpsampler(UpsampleOptions options = {});

    // `low_color`: linear RGBA at lw x lh (see above), rendered with `jitter_px` (full-resolution
    // pixels). `full`: this frame's full-resolution guides; depth is required and sets the size,
    // normal, id and motion may be empty (their tests and the history are then skipped).
    // `out`: the full size, caller-owned, must not alias the inputs. The first frame, a new size
    // and the frame after reset() are spatial only. Threaded; allocates only on a size change.
    // Frames must come in order: the history moves by one frame's motion, so after a skipped or
    // lost frame call reset() (otherwise only the depth and id tests stand between the stale
    // history and the picture).
    void upsample(ImageView<const glm::vec4> low_color, glm::vec2 jitter_px,
                  const GBufferView& full, ImageView<glm::vec4> out,
                  UpsampleStats* stats = nullptr);
    // Forgets the history (a cut, a new stream).
    void reset();

    const UpsampleOptions& options() const { return options_; }

private:
    struct Pass;  // one frame's context (upsample.cpp)
    void resize(int width, int height);
    void fetch_history(Pass& pass);  // (A)
    void temporal_gradient(const Pass& pass, int x, int y);
    void smooth_gradient(const Pass& pass);             // (B)
    void filter(Pass& pass, ImageView<glm::vec4> out);  // (C)
    void keep_history(const Pass& pass);                // (D)

    UpsampleOptions options_;
    // History, double-buffered (read at p + motion while the next one is written).
    Image<glm::vec4> history_, next_history_;  // h_r rgb, a = h_w
    Image<glm::vec4> deltas_, next_deltas_;    // the last three relative differences
    Image<float> history_depth_;
    Image<uint32_t> history_id_;
    // Per-frame scratch, sized once.
    Image<glm::vec4> reprojected_;  // h_r at p + motion, a = h_w (0: no history)
    Image<float> gradient_, gradient_tmp_;
    // The 2x2 spatial taps of each pixel (geometric weights, filter bases), shared by the gradient
    // and the final pass.
    Image<glm::vec4> tap_geometric_, tap_base_;
    glm::vec2 history_jitter_{0.0f};  // the full G-buffer's jitter of the history's frame
    bool history_has_ids_ = false;
    bool has_history_ = false;
    NonfiniteRepair guide_repair_;
};

}  // namespace reprise::warp
