#pragma once
// The display-rate paths on the GPU through OpenGL ES 3.1 compute shaders: one Context owns the
// GL context, the programs and the textures, sized once per frame size (per-frame calls allocate
// nothing while the size stays). Two ways in: CPU images (the same G-buffer descriptor and
// options as warp/, uploaded and downloaded) and GL textures an application already has, made in
// this context (make_current()), written without a CPU round trip.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "reprise/core/gbuffer.hpp"
#include "reprise/core/nonfinite.hpp"
#include "reprise/core/status.hpp"
#include "reprise/stereo/synthesize.hpp"
#include "reprise/warp/fill.hpp"
#include "reprise/warp/fruc.hpp"
#include "reprise/warp/grid_warp.hpp"
#include "reprise/warp/reproject.hpp"
#include "reprise/warp/shot_change.hpp"
#include "reprise/warp/splat.hpp"

namespace reprise::gl {
class Context;
}

namespace reprise::gpu {

// What the last call spent, in milliseconds, each phase finished (glFinish) before the next.
// `cpu_ms`: the work a path leaves on the CPU (the flow of motion refinement; for skewed
// projections the grid's displacement and cells, and the widened silhouettes they start from),
// apart from the transfers and the GPU's compute.
struct Timings {
    double cpu_ms = 0.0;
    double upload_ms = 0.0;
    double compute_ms = 0.0;
    double download_ms = 0.0;
};

// A G-buffer already on the GPU: texture names with their units as GBufferView's.
struct GBufferTextures {
    unsigned depth = 0;   // GL_R32F: linear view depth, +inf background
    unsigned motion = 0;  // GL_RG32F: backward motion in pixels
    unsigned id = 0;      // GL_R32UI: object ids; 0 = none
    int width = 0;
    int height = 0;
    Camera camera;
};

// A frame's planes already on the GPU, each 0 where not (gpu::Upsampler's kept output and its
// guides, FrucBackend::inputs_from): colour GL_RGBA32F (finite), depth GL_R32F and motion
// GL_RG32F (both or neither, NaN/Inf repaired as the CPU-image entries repair them), all of the
// frame's size and holding its pixels.
struct FrameOnGpu {
    unsigned color = 0, depth = 0, motion = 0;
};

// A frame made on the GPU and kept there: colour GL_RGBA32F (linear light), depth GL_R32F,
// backward motion per period in the RG of a GL_RGBA32F texture.
struct MadeTextures {
    unsigned color = 0, depth = 0, motion = 0;
    int width = 0, height = 0;
};

// What an in-between frame took: covered pixels of each side, pixels neither covered, the
// fill's stats (all zero when there were no holes: no fill), and the NaN/Inf the CPU-image entry
// repaired in its inputs (as the CPU converter does).
struct InterpolateStats {
    // holes: those the fill was given, after `border` of them were continued from their row
    // (warp::continue_border_rows, InterpolateOptions::border_run), as the CPU counts them.
    std::size_t covered_a = 0, covered_b = 0, holes = 0, border = 0;
    std::size_t grid_cells = 0;  // cells the grid drew, both sides (FrucCounters::grid_cells)
    // Pixels of a and of b given a nearer neighbour's surface (InterpolateOptions::
    // widen_silhouettes), counted when the input is widened: after its upload, or again where
    // a texture-entry call or widening off came between (0 where a kept upload's widening was
    // kept too).
    std::size_t silhouette_a = 0, silhouette_b = 0;
    bool true_motion = false;    // the sides followed their true motion
    bool linear_motion = false;  // ... had it been asked for, but a survey found it linear
    warp::FillStats fill;
    NonfiniteCounts nonfinite;
    int uploads_kept = 0;  // inputs whose key matched: an earlier call's upload reused (0-2)
    // Motion refinement (InterpolateOptions::refine): FrucCounters' fields of the same names for
    // this frame; refine_skipped where nothing disagreed.
    bool refine_skipped = false;
    std::size_t refine_tiles = 0, refine_tiles_left_out = 0, flow_pixels = 0, refined_pixels = 0;
    double refine_ms = 0.0;  // the survey, the flow and the choice, wall clock
};

// What an extrapolated frame took: pixels its camera does not explain (carried along their own
// motion; every pixel when the frame has no camera), covered pixels, pixels nothing covered, the
// fill's stats (zero when nothing was a hole) and the NaN/Inf the CPU-image entry repaired.
struct ExtrapolateStats {
    std::size_t moving = 0, covered = 0, holes = 0,
                border = 0;      // holes, border: as interpolation's
    std::size_t grid_cells = 0;  // cells the grid drew
    // Pixels given a nearer neighbour's surface (FrucOptions::widen_silhouettes), counted when
    // the frame is uploaded (0 when the upload was kept).
    std::size_t silhouette_pixels = 0;
    warp::FillStats fill;
    NonfiniteCounts nonfinite;
    bool upload_kept = false;  // the frame key matched: the last call's upload was reused
};

// How Context::interpolate makes the in-between frame (FrucOptions' fields of the same names).
struct InterpolateOptions {
    warp::SplatOptions splat;
    bool reverse = false;  // WarpMethod::Reverse: a footprint-2 splat whose colour is refetched
    bool grid = false;     // WarpMethod::Grid: each side by the adaptive grid (`grid_options`)
    warp::GridOptions grid_options;
    // Each side along its true motion (static pixels through depth to the in-between camera,
    // a's moving ones along b's motion inverted) unless warp's survey finds it linear (on
    // textures, its sampled pixels are gathered and read back: 1/64 of the depth and motion).
    bool true_motion = false;
    float static_tolerance = 0.25f;
    float motion_scale = 1.0f;  // the made frame's motion: per output period
    // Motion refinement, off unless asked (FrucOptions' is on): the survey, the flow's grey
    // crops, its evaluation and the choice on the GPU, the flow itself (OpenCV's DIS over the
    // boxes around the disagreeing tiles) on the CPU: the crops come back, the flow goes up.
    warp::RefineOptions refine{.enabled = false};
    int border_run = warp::kMadeFrameBorderRun;  // FrucOptions::border_run
    bool widen_silhouettes = true;               // FrucOptions::widen_silhouettes
};

struct ContextState;  // GL objects and scratch (private)

class Context {
public:
    // Creates its own EGL context (gl::Context: a GPU's EGL device, else Mesa llvmpipe).
    static Status create(std::unique_ptr<Context>& context);
    // Works in the application's OpenGL ES 3.1+ context current on this thread instead: its
    // textures are used as they are, nothing is made current, and every call (and the
    // destruction, which deletes this Context's GL objects) needs that context current on the
    // calling thread. A call leaves the texture, sampler, program, image, buffer and framebuffer
    // bindings it used at 0.
    static Status adopt_current(std::unique_ptr<Context>& context);
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    void make_current() const;
    const std::string& description() const;  // the GL renderer and version
    const Timings& timings() const { return timings_; }

    // warp::reproject on the GPU, for an RGBA payload (4 channels): the same lookups, depth and
    // id tests and counts; `out` keeps its values where the lookup misses, `hit` (may be empty)
    // gets 1 / 0 at every looked-up pixel.
    Status reproject(const GBufferView& current, const GBufferView& previous,
                     warp::ConstPayload previous_payload, warp::Payload out, ImageView<uint8_t> hit,
                     const warp::ReprojectOptions& options, warp::ReprojectCounts& counts);
    // The same on textures: `payload` and `out` GL_RGBA32F of the previous frame's and the
    // current frame's size, `hit` GL_R32UI of the current size (0: none).
    Status reproject(const GBufferTextures& current, const GBufferTextures& previous,
                     unsigned payload, unsigned out, unsigned hit,
                     const warp::ReprojectOptions& options, warp::ReprojectCounts& counts);

    // warp::PullPush::fill on the GPU as a mip chain: the same holes (valid == 0 or non-finite
    // RGB), the same depth-aware pull and push, the same stats; only the RGB of holes changes.
    Status fill(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                ImageView<const float> depth, warp::FillStats& stats);
    // The same on textures: `color` GL_RGBA32F, `valid` GL_R8UI, `depth` GL_R32F (0: none), all
    // width x height; the filled colour goes to `out` (GL_RGBA32F, not `color`).
    Status fill(unsigned color, unsigned valid, unsigned depth, int width, int height, unsigned out,
                warp::FillStats& stats);

    // warp::widen_silhouettes on textures (the paths below widen their inputs themselves, as
    // their options say): `frame.depth` (GL_R32F) and `frame.motion` (GL_RG32F; 0: none, depth
    // alone widened) into `out_depth` (GL_R32F) and `out_motion` (GL_RGBA32F, the motion in RG;
    // unused without motion), all of the frame's size; `changed` gets the pixels that took a
    // nearer neighbour's depth and motion.
    Status widen_silhouettes(const GBufferTextures& frame, unsigned out_depth, unsigned out_motion,
                             std::size_t& changed);

    // warp::splat on the GPU. Among the candidates within the depth tolerance of a pixel's
    // nearest one, the one landing nearest its centre wins, ties to the first in source order
    // (the CPU z-tests in source order against the one stored: the same where candidates do not
    // chain across the tolerance). `covered` gets the covered pixel count.
    Status splat(const GBufferView& source, float factor, const warp::WarpTarget& target,
                 const warp::SplatOptions& options, std::size_t& covered);

    // warp::GridWarper::warp on the GPU: its cells grown by a compute shader (the CPU's
    // GridWarper::cells, the same cells in the same order), drawn by GL's rasteriser with the
    // CPU's edge functions, attribute planes, clamps and depth test. Needs storage buffers in
    // vertex shaders and float colour attachments (an error says so).
    Status grid_warp(const GBufferView& source, float factor, const warp::WarpTarget& target,
                     const warp::GridOptions& options, warp::GridStats& stats);
    // The cells grid_warp grows, read back (what GridWarper::cells gives on the CPU).
    Status grid_cells(const GBufferView& source, float factor, const warp::GridOptions& options,
                      std::vector<warp::GridCell>& cells);
    // stereo::StereoSynthesizer::synthesize for StereoFill::PullPush or None (others are an
    // error): displacement through depth, the splat or the grid (its cells grown on the GPU), the
    // `history` (e.g. the previous frame's other eye, its moving pixels left out) warped the same
    // way into the holes (and the grid's stretched pixels), the grid's border strip continued,
    // pull-push, non-finite colour to 0. Cameras without jitter; a skewed projection only for
    // the grid on CPU images (its displacement and cells then made on the CPU).
    Status stereo_eye(const GBufferView& rendered, const Camera& target, Frame& out,
                      stereo::StereoStats& stats, const stereo::StereoOptions& options = {},
                      const GBufferView* history = nullptr);
    // The same on textures: `rendered.depth` and `color` (GL_RGBA32F) in, `out_color`
    // (GL_RGBA32F) and `out_depth` (GL_R32F) written, all of the rendered size. No repair of
    // NaN/Inf input here (the CPU-image entry repairs as the CPU does): pixels with NaN depth are
    // left out, colour with a non-finite channel comes out 0. Silhouettes are widened on the GPU
    // by both entries (StereoOptions::widen_silhouettes; on the CPU for a skewed grid's). A
    // `history` (its depth, motion (0: none, nothing left out) and camera, colour
    // `history_color`, of the rendered size) fills the holes as in the CPU-image entry.
    Status stereo_eye(const GBufferTextures& rendered, unsigned color, const Camera& target,
                      unsigned out_color, unsigned out_depth, stereo::StereoStats& stats,
                      const stereo::StereoOptions& options = {},
                      const GBufferTextures* history = nullptr, unsigned history_color = 0);

    // The frame at `s` in [0, 1] between a (0) and b (1) with b's backward motion: warp's
    // interpolate_frame for FrucOptions{.warp = Splat, Reverse or Grid} and pull-push: b warped
    // by 1 - s, a by -s (along their true motion with options.true_motion), blended by s where
    // both land on one surface (depths within 15 %; where only one side was drawn by a
    // stretched grid triangle, the other), the nearer or the only one elsewhere, each row's
    // border strip continued (options.border_run px), pull-push over the other holes, and with
    // options.refine the flow's colour where it wins (the flow
    // on the CPU: Timings::cpu_ms). Colour, depth and motion out: the motion the winning side
    // carried (b's where both are blended) times motion_scale, as the CPU's (normal and id
    // cleared; out.camera is b's).
    // NaN/Inf in a and b are repaired first, as the CPU converter does (the texture entry does
    // not repair); then their silhouettes are widened on the GPU (options.widen_silhouettes).
    // Non-zero keys equal to the last call's a or b key reuse that input's upload (b's becoming a's
    // when the next pair starts): the caller promises the same frame.
    Status interpolate(const GBufferView& a, const GBufferView& b, float s, Frame& out,
                       InterpolateStats& stats, const InterpolateOptions& options = {},
                       uint64_t a_key = 0, uint64_t b_key = 0);
    // The same on textures: colour GL_RGBA32F, depth GL_R32F, motion GL_RG32F, all one size;
    // `out_color` and `out_depth` written, and `out_motion` (GL_RGBA32F, the motion in RG; 0:
    // not written).
    Status interpolate(const GBufferTextures& a, unsigned a_color, const GBufferTextures& b,
                       unsigned b_color, float s, unsigned out_color, unsigned out_depth,
                       InterpolateStats& stats, const InterpolateOptions& options = {},
                       unsigned out_motion = 0);

    // warp::PoseExtrapolator (and the converter's extrapolation) for FrucOptions with warp Splat
    // or Reverse (on CPU images also Grid: warp::extrapolation_displacement and the grid's cells
    // on the CPU, drawn by the GPU) and fill PullPush or None (others are an error): `frame` as
    // seen by (view, projection) `periods` frame periods after it. Static pixels (their motion
    // within options.static_tolerance px of the camera's alone) go where that camera sees them, the
    // others `periods` along their own motion, in one splat; each row's border strip continued
    // (FrucOptions::border_run px), pull-push over the other holes.
    // A frame without a projection goes along its motion alone (view and projection unused).
    // out gets colour, depth and backward motion per period times motion_scale (0 at periods
    // 0); out.normal and id cleared, out.camera untouched. NaN/Inf are repaired first, as the
    // converter does (PoseExtrapolator does not: on such input the GPU makes the CPU's frame of
    // the repaired input); the silhouettes widened on the GPU (options.widen_silhouettes).
    // A non-zero `frame_key` equal to the last call's reuses that call's upload (and its repair
    // counts): the caller promises the same frame, pixels unchanged. Planes `on_gpu` names are
    // copied (or widened) on the GPU instead of uploaded; frame.color is then not read, frame's
    // depth and motion only repaired to count what was repaired (and for the grid's cells on the
    // CPU, skewed projections).
    Status extrapolate(const GBufferView& frame, const glm::mat4& view, const glm::mat4& projection,
                       float periods, Frame& out, ExtrapolateStats& stats,
                       const warp::FrucOptions& options, float motion_scale = 1.0f,
                       uint64_t frame_key = 0, const FrameOnGpu& on_gpu = {});
    // The same with the made frame left on the GPU, nothing downloaded: made() names its
    // textures (a display that draws them, `reprise connect --backend gles --window`).
    Status extrapolate_on_gpu(const GBufferView& frame, const glm::mat4& view,
                              const glm::mat4& projection, float periods, ExtrapolateStats& stats,
                              const warp::FrucOptions& options, float motion_scale = 1.0f,
                              uint64_t frame_key = 0, const FrameOnGpu& on_gpu = {});
    // What the last extrapolate call on CPU images made, until the next call of any kind (the
    // textures are the context's scratch); all 0 when that call failed or made nothing.
    MadeTextures made() const;
    // The same on textures: `color` GL_RGBA32F beside frame's depth and motion; `out_color`
    // (GL_RGBA32F), `out_depth` (GL_R32F) and `out_motion` (GL_RGBA32F with the motion in RG, as
    // GL ES has no RG32F image format; 0: not written), all of the frame's size. No repair;
    // silhouettes widened as options say.
    Status extrapolate(const GBufferTextures& frame, unsigned color, const glm::mat4& view,
                       const glm::mat4& projection, float periods, unsigned out_color,
                       unsigned out_depth, unsigned out_motion, ExtrapolateStats& stats,
                       const warp::FrucOptions& options, float motion_scale = 1.0f);

    // warp::shot_change on the GPU: the survey's reprojection, then each hit's display difference
    // (the CPU's table and arithmetic) summed exactly; the same counts, sum and decision as the
    // CPU. Frames without depth or motion, or a previous frame without depth, are never a cut.
    Status shot_change(const GBufferView& frame, const GBufferView& previous, float cut_misses,
                       float cut_color, warp::ShotChange& result);
    // The same on textures: each frame's colour (GL_RGBA32F) beside its G-buffer (ids where both
    // have them); the frame's depth and motion and the previous depth are required here.
    Status shot_change(const GBufferTextures& frame, unsigned frame_color,
                       const GBufferTextures& previous, unsigned previous_color, float cut_misses,
                       float cut_color, warp::ShotChange& result);

private:
    friend class Upsampler;  // its passes run on this context's state
    Context();
    static Status create_on(std::unique_ptr<gl::Context> gl, std::unique_ptr<Context>& context);
    std::unique_ptr<ContextState> state_;
    Timings timings_;
};

}  // namespace reprise::gpu
