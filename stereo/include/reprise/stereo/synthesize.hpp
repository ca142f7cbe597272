#pragma once
// The second eye from one rendered eye: per-pixel displacement from depth and the two cameras,
// a forward warp (adaptive grid or splat) with a depth test, history from an earlier frame,
// then hole filling from the background side.
#include <cstddef>
#include <cstdint>
#include <memory>

#include "reprise/core/nonfinite.hpp"
#include "reprise/warp/fill.hpp"
#include "reprise/warp/grid_warp.hpp"
#include "reprise/warp/splat.hpp"

namespace reprise::stereo {

enum class StereoWarp { Grid, Splat };
enum class StereoFill { None, PullPush, Andreev, Patch };  // Patch: warp::PatchFill

struct StereoOptions {
    StereoWarp warp = StereoWarp::Grid;
    StereoFill fill = StereoFill::PullPush;
    // One-pixel smallest cells (GridOptions' default): two-pixel ones drew silhouettes as two-pixel
    // stairs (the eye's edges are not blended with another side as an in-between frame's are).
    // Measured on bench stereo: +0.74 dB mean over the built-in scenes (pan +1.85, hud +1.88,
    // shadows +2.53, stroll +1.19; specular -0.59, crossing -0.27, courtyard -0.16), +0.2 to +0.8
    // on the Blender renders, at the same time. Colour fetched bicubically, as the in-between
    // frame's (warp::FrucOptions::grid): docs/benchmarks.md has bench stereo with both fetches.
    warp::GridOptions grid{.bicubic = true};
    warp::SplatOptions splat;
    // History and current warp show the same surface when their depths differ by less than this
    // fraction; the history (a view nearer the target, with its own view-dependent shading) then
    // wins if its camera stood closer to the target than the rendered one — only when
    // history_replaces is set: the history is warped as if nothing moved, so on scenes with moving
    // objects it puts their texture where they were (crossing: -14 dB). By default it fills holes.
    float history_depth_tolerance = 0.01f;
    bool history_replaces = false;
    // History pixels whose motion (from the frame before it) its camera does not explain within
    // this many pixels are left out: the history shows moving objects where they were, and would
    // fill the holes beside them with their stale copy. +inf keeps them; a history without
    // motion keeps them all.
    float history_moving_tolerance = 0.5f;
    // Edge pixels go with the nearer surface, as in frame-rate conversion
    // (warp::widen_silhouettes, warp::FrucOptions::widen_silhouettes).
    bool widen_silhouettes = true;
    // Colour warped and filled as the square root of linear light, as in frame-rate conversion
    // (warp/perceptual.hpp, warp::FrucOptions::perceptual). The GPU's eye (gpu::Context::
    // stereo_eye) works in linear light.
    bool perceptual = true;
};

struct StereoStats {
    std::size_t covered = 0;  // pixels the rendered eye's warp covered
    std::size_t holes = 0;    // pixels it left empty
    // ... covered only by a grid triangle stretched over a disocclusion (warp::kCoveredStretched):
    // taken from the history where it saw them, else left to pull-push (other fills keep them)
    std::size_t stretched = 0;
    std::size_t from_history = 0;    // pixels taken from the history view
    std::size_t history_moving = 0;  // history pixels left out as moving (history_moving_tolerance)
    // Grid eye: holes at the image's left and right edges that continue their row's outermost
    // covered pixel (what the made eye sees beyond the rendered one's view).
    std::size_t border = 0;
    std::size_t filled = 0;    // pixels invented by the hole filler
    std::size_t unfilled = 0;  // holes left (no fill, or nothing to fill from): colour 0
    std::size_t cells = 0;     // grid cells drawn (both warps)
    // NaN/Inf in the rendered eye and the history, repaired before warping (colour: holes;
    // depth NaN/-inf and motion: unknown; see reprise/core/nonfinite.hpp).
    NonfiniteCounts nonfinite;
};

// Sizes its scratch on the first frame and reuses it while the size stays the same.
class StereoSynthesizer {
public:
    // Makes the view of `target` from `rendered` (colour + depth + camera) into out.color,
    // out.depth and out.camera (out.motion, normal and id are cleared; out.fps is left as it is).
    // Displacements are exact for static geometry: each pixel is unprojected with the rendered
    // camera and projected with the target (background +inf by its direction). `history` (may be
    // null), an earlier view with colour, depth and camera, e.g. the previous frame's other eye, is
    // warped to the target the same way and fills the holes first. When the rendered frame's
    // motion is all zero (still camera and scene) and the history's camera is the target, the
    // history is already the target view and is returned as it is. Cameras without jitter;
    // projections perspective or orthographic without skew.
    StereoStats synthesize(const GBufferView& rendered, const Camera& target, Frame& out,
                           const StereoOptions& options = {}, const GBufferView* history = nullptr);
    StereoStats synthesize(const GBufferView& rendered, const Camera& target, Frame& out,
                           const StereoOptions& options, const Frame* history) {
        const GBufferView h = history ? history->view() : GBufferView{};
        return synthesize(rendered, target, out, options, history ? &h : nullptr);
    }

    // 1 where the last synthesis covered the pixel from the rendered eye (size of the output).
    ImageView<const uint8_t> coverage() const { return covered_.view(); }

private:
    // Warps `source` to `target` into `into`; returns the covered pixel count (cells in `cells`;
    // `maybe_nonfinite` set when covered colour may hold NaN or infinity). With `moving`, its
    // moving pixels are left out and counted there.
    std::size_t warp_into(const GBufferView& source, const Camera& target, const StereoOptions& o,
                          const warp::WarpTarget& into, std::size_t& cells, bool& maybe_nonfinite,
                          std::size_t* moving = nullptr);

    Image<glm::vec2> displacement_;  // the source's displacement to the target, as motion
    Image<float> target_depth_;      // and its depth seen from the target
    Image<float> wide_depth_;        // the source's depth and motion with its silhouettes widened
    Image<glm::vec2> wide_motion_;
    Image<glm::vec4> encoded_color_;  // the source's colour for StereoOptions::perceptual
    Image<uint8_t> covered_;
    Image<glm::vec4> history_color_;
    Image<float> history_depth_;
    Image<uint8_t> history_covered_;
    Image<uint8_t> valid_;
    warp::GridWarper grid_;
    warp::PullPush pull_push_;
    warp::AndreevInpaint andreev_;
    warp::PatchFill patch_;
    NonfiniteRepair rendered_repair_, history_repair_;
};

// One-shot form (allocates its scratch per call).
StereoStats synthesize_eye(const GBufferView& rendered, const Camera& target,
                           const StereoOptions& options, Frame& out,
                           const GBufferView* history = nullptr);

// Per-pixel displacement (pixels, as backward-motion-style offsets: p + d is where pixel p of
// `source` lands in `target`) and the landing depth in the target camera. NaN where the point
// is invalid (NaN or negative depth) or lands behind the target camera.
// The size is the depth's.
void stereo_displacement(const GBufferView& source, const Camera& target,
                         ImageView<glm::vec2> displacement, ImageView<float> target_depth);

// Leaves out of a history's warp (NaN displacement) the pixels of `source` whose motion its
// camera does not explain within `tolerance` px: they are not where they were. Returns how many;
// without motion, none.
std::size_t drop_moving(const GBufferView& source, float tolerance,
                        ImageView<glm::vec2> displacement);

}  // namespace reprise::stereo
