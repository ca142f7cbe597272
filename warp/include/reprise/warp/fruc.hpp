#pragma once
// Frame-rate upconversion: K output frames per rendered frame, by interpolation between the last
// two frames or by extrapolation from the last one alone (no added latency).
#include <array>
#include <cstddef>
#include <memory>
#include <string>

#include "reprise/core/nonfinite.hpp"
#include "reprise/warp/fill.hpp"
#include "reprise/warp/grid_warp.hpp"
#include "reprise/warp/reproject.hpp"
#include "reprise/warp/splat.hpp"

namespace reprise::warp {

enum class FrucMode { Interpolate, Extrapolate };
enum class WarpMethod {
    Reverse,  // splat motion to the new instant, then fetch colour bilinearly (both sides)
    Splat,    // forward splat of colour (2x2 footprint)
    Grid,     // adaptive-grid warp
    Auto,     // per frame, the cheapest expected to meet AutoOptions' budget (with the fill)
};
// Patch: frequency-selective reconstruction (PatchFill); not a candidate of the automatic choice
// (warp Auto with fill Patch is refused).
enum class FillMethod { None, PullPush, Andreev, Auto, Patch };

// The per-frame choice of `--warp auto --fill auto`: every fixed warp x fill is a candidate, its
// error and cost predicted from a survey of the input (FramePredictors) by models fitted to
// measured runs (docs/benchmarks.md, "Automatic choice"). A fixed warp or fill limits the
// candidates to those with it.
struct AutoOptions {
    // The PSNR (dB, display values) a made frame should reach: the cheapest candidate expected to
    // reach it is taken, or the best expected one when none is. 0: relative to the best expected
    // candidate of each frame, the cheapest within slack_db of it.
    float budget_db = 0.0f;
    float slack_db = 0.25f;
};

// What the choice knows of a frame before warping anything, from every 8th pixel of every 8th
// row of the frame the warp starts from, per input period of motion.
struct FramePredictors {
    float motion = 0.0f;       // mean motion length, px
    float spread = 0.0f;       // RMS deviation of the motion from its mean, px
    float disoccluded = 0.0f;  // fraction of the frame uncovered across depth edges (depth-only)
    bool any_motion = false;   // some surveyed motion is not zero
};
FramePredictors survey_predictors(const GBufferView& frame);

// Candidates in the order reverse, splat, grid (warp) x none, pullpush, andreev (fill).
inline constexpr int kAutoCandidates = 9;
WarpMethod auto_candidate_warp(int candidate);
FillMethod auto_candidate_fill(int candidate);
const char* auto_candidate_name(int candidate);  // "grid+pullpush"

// The models at `distance` input periods from the nearer input frame (interpolation) or
// beyond it (extrapolation): expected PSNR (dB) and cost (ns per pixel) of a candidate.
struct AutoPrediction {
    std::array<float, kAutoCandidates> psnr{};
    std::array<float, kAutoCandidates> cost{};
};
AutoPrediction predict_candidates(const FramePredictors& p, float distance, FrucMode mode);

// The candidate chosen for `prediction` among those `options` allows (fixed warp or fill).
int choose_candidate(const AutoPrediction& prediction, WarpMethod warp, FillMethod fill,
                     const AutoOptions& options);

// Motion refinement of interpolation: rendered motion is the motion of surfaces, not of what is
// seen on them (moving shadows, reflections, highlights). Where the two sides of an in-between
// frame, warped along rendered motion, show the same surface (no disocclusion: both sides cover
// it at one depth) in colours that differ, optical flow (OpenCV DIS) between the two input frames
// is estimated on those tiles alone, and each of their pixels takes the flow's colour where the
// flow's two sides agree better than the rendered motion's. Frames without disagreement pay one
// survey of every 2nd pixel of every 2nd row.
struct RefineOptions {
    bool enabled = true;
    int tile = 16;            // px: disagreement is decided and flow evaluated per tile
    float threshold = 0.1f;   // display-value difference (largest channel) of disagreeing sides
    float tile_share = 0.1f;  // share of a tile's surveyed pixels that must disagree
    int margin = 16;          // px of context around the disagreeing tiles given to the flow
    // Also decide the ring of tiles around the disagreeing ones: boxes 2.4x the pixels on pan at
    // 1080p for 0.14-0.28 dB more over whole frames on pan and mirror (docs/benchmarks.md).
    bool neighbours = true;
    // Largest share of the frame's pixels the flow runs on: the boxes that disagree most per
    // pixel go first, the tiles of the others are left out (FrucCounters::refine_tiles_left_out).
    float max_flow_share = 1.0f;
};

struct FrucCounters;
struct FrucOptions;

// Makes the warped frames of a FrameRateConverter or a PoseExtrapolator elsewhere than on the
// CPU (a GPU: gpu::FrucBackend). The caller keeps the rest — order, cuts, still pairs, repair,
// widened silhouettes (unless the backend widens them), UI — and hands the backend the inputs its
// own warps would take, in linear light (FrucOptions::perceptual is the CPU's). An error
// from it ends send() (or extrapolate()) with that error and leaves the converter as it was
// before that send().
class WarpBackend {
public:
    virtual ~WarpBackend() = default;
    // The options the backend makes the same frames for as the CPU; an error says why not.
    virtual Status supports(const FrucOptions& options) const = 0;
    // Whether the backend widens its inputs' silhouettes itself (FrucOptions::widen_silhouettes,
    // counted into FrucCounters::silhouette_pixels): then it is handed them as they are, and told
    // of an input the converter widened and counted on the CPU (a frame it made there, after a
    // cut), so that each input is counted once.
    virtual bool widens_silhouettes() const { return false; }
    virtual void silhouettes_counted(uint64_t /*frame_key*/) {}
    // What interpolate_frame makes with both sides warpable: the frame at s between a and b,
    // colour, depth and motion times motion_scale (its motion may stay empty). Non-zero keys,
    // the same for the same frame, say which frames a and b are (the converter's input keys: a
    // pair gives several frames at x3 and more, and b becomes the next pair's a): a backend may
    // keep what it made of them (gpu::FrucBackend keeps them uploaded).
    virtual Status interpolate(const GBufferView& a, const GBufferView& b, float s,
                               float motion_scale, const FrucOptions& options, Frame& out,
                               FrucCounters& counters, uint64_t a_key, uint64_t b_key) = 0;
    // What the CPU's extrapolation makes: f as seen by (view, projection) `periods` frame
    // periods after it (without a projection on f: along its motion alone), colour, depth and
    // backward motion per period times motion_scale. A backend may repair NaN/Inf in f first
    // (gpu::FrucBackend does; the converter's inputs are repaired already). A non-zero
    // `frame_key` equal to the previous call's says f is that frame again, pixels unchanged (a
    // display loop extrapolates one decoded frame many times): a backend may keep what it made
    // of it (gpu::FrucBackend keeps it uploaded).
    virtual Status extrapolate(const GBufferView& f, const glm::mat4& view,
                               const glm::mat4& projection, float periods, float motion_scale,
                               const FrucOptions& options, Frame& out, FrucCounters& counters,
                               uint64_t frame_key) = 0;
};

struct FrucOptions {
    FrucMode mode = FrucMode::Interpolate;
    WarpMethod warp = WarpMethod::Grid;
    FillMethod fill = FillMethod::PullPush;
    // The grid fetches colour bicubically: on anti-aliased renders it measured 0.6-1.1 dB above the
    // bilinear fetch (docs/benchmarks.md). The stereo eye fetches bicubically too (StereoOptions).
    GridOptions grid{.bicubic = true};
    // Edge pixels go with the nearer surface (widen_silhouettes, reprise/warp/silhouettes.hpp):
    // their blended colour travels with the silhouette instead of staying on the background as a
    // ghost contour.
    bool widen_silhouettes = true;
    // Colour is warped, blended and filled as the square root of linear light (a scale close to
    // the display's), then squared back: resampled and blended edges, and pixels blended from
    // both sides, come out nearer what the display shows of the rendered truth (docs/benchmarks.md,
    // "Blending on the display's scale"). Off: in linear light. A converter with a backend
    // (gpu::FrucBackend) works in linear light, the frames it makes on the CPU too.
    bool perceptual = true;
    SplatOptions splat;
    // A new frame whose camera does not say whether a cut came before it (Camera::cut Unknown) and
    // whose reverse reprojection into the previous one misses on more than this fraction of pixels,
    // or whose hits differ in mean display colour by more than cut_color, starts a new shot: the
    // history is dropped, nothing is blended across it.
    float cut_misses = 0.6f;
    float cut_color = 0.12f;
    // A pixel is static when its motion differs from the camera-only motion by less than this
    // many pixels.
    float static_tolerance = 0.25f;
    // Interpolation with cameras: each side goes where it truly is at the in-between instant —
    // static pixels along depth and the in-between camera (exact under rotation and acceleration),
    // the earlier frame's moving pixels along the later frame's motion inverted. Off: the earlier
    // frame follows its own backward motion negated, both sides linearly.
    bool true_motion = true;
    RefineOptions refine;
    // The UI layer (Frame::ui): a made frame takes the UI of the nearest input (the later one at
    // equal distance), never warped. Off: kept in the made frame's ui channels; on: drawn over
    // the colour of every output (inputs too), which then carries no ui channels.
    bool composite_ui = false;
    AutoOptions auto_choice;  // warp or fill Auto
    // Not owned; null: the CPU. It must outlive the converter.
    WarpBackend* backend = nullptr;
    // Before a made frame's fill, up to this many holes beside each row's outermost covered pixel
    // take its colour and depth (warp::continue_border_rows): what a panning camera uncovers at
    // the border continues the row. 0: the fill alone. Not with FillMethod::None.
    int border_run = kMadeFrameBorderRun;
};

// What was done and what was left out because the frame did not need it.
struct FrucCounters {
    std::size_t inputs = 0;
    std::size_t outputs = 0;        // frames made (inputs passed through are not counted)
    std::size_t copied_still = 0;   // zero motion: exact copy, nothing warped
    std::size_t fills = 0;          // frames whose holes were filled
    std::size_t fills_skipped = 0;  // no holes: no fill
    std::size_t hole_pixels = 0;    // holes the fill was given (after the border strips)
    std::size_t border_pixels = 0;  // holes at the border continued from their row first
    std::size_t dynamic_layers =
        0;  // extrapolation: frames with pixels the camera does not explain
    std::size_t dynamic_skipped = 0;    // ... without: every pixel follows the camera
    std::size_t cuts = 0;               // shot changes (the camera's Cut::Yes, or detected)
    std::size_t cut_tests_skipped = 0;  // frames whose camera said whether a cut came: no test
    std::size_t grid_cells = 0;         // adaptive-grid cells drawn
    std::size_t silhouette_pixels = 0;  // input pixels given a nearer neighbour's surface (once
                                        // per input in a converter)
    std::size_t true_motion = 0;        // in-between frames whose sides followed the true motion
    std::size_t linear_motion = 0;      // ... that did not need it: a sparse survey found it linear
    std::size_t refined_frames = 0;     // in-between frames whose sides disagreed: flow estimated
    std::size_t refine_skipped = 0;     // ... whose sides agreed everywhere: nothing estimated
    std::size_t refine_tiles = 0;       // tiles whose sides disagreed
    std::size_t refine_tiles_left_out = 0;  // ... not refined: past RefineOptions::max_flow_share
    std::size_t flow_pixels = 0;     // pixels the flow was estimated on (boxes around the tiles)
    std::size_t refined_pixels = 0;  // pixels that took the flow's colour
    double refine_ms = 0.0;          // time in the survey and the refinement
    std::size_t ui_frames = 0;       // made frames given the nearest input's UI layer
    // NaN/Inf in the inputs, repaired before anything is warped (reprise/core/nonfinite.hpp).
    NonfiniteCounts nonfinite;
    // Auto choice, per candidate (auto_candidate_name): frames it was chosen for, and frames it
    // was left out of although expected to score higher than the choice (too costly for it).
    std::array<std::size_t, kAutoCandidates> auto_chosen{};
    std::array<std::size_t, kAutoCandidates> auto_left_out{};
};

// Settings by name, as `reprise fruc` and Python take them: mode interpolate | extrapolate;
// warp reverse | splat | grid | grid-bicubic | grid-bilinear | auto; fill pullpush | andreev |
// none | auto. An unknown name: an error naming the setting, the name and the choices.
Status fruc_options_from_names(const std::string& mode, const std::string& warp,
                               const std::string& fill, FrucOptions& options);
// Output frames per input frame a FrameRateConverter makes: 1..kMaxFrucFactor.
inline constexpr int kMaxFrucFactor = 16;
Status check_fruc_factor(int factor);

// The camera between or beyond two instants: view matrices blended as rigid motions (rotation
// slerp, translation lerp, s may exceed 1), the projection taken from `b`.
Camera camera_between(const Camera& a, const Camera& b, float s);

// True when a survey of every 8th pixel of every 8th row finds nothing moving on its own and every
// static pixel landing within 0.02 px of p + factor * motion in camera `to`: the true motion is
// then the linear one (an in-between frame with FrucOptions::true_motion takes the linear path).
bool motion_is_linear(const GBufferView& f, const Camera& to, float factor, float tolerance);

// The options' values in their ranges: an error naming the first that is not.
Status check_fruc_options(const FrucOptions& options);

class FrameRateConverter {
public:
    FrameRateConverter();  // factor 2, default options
    // Checks the factor (check_fruc_factor) and the options (check_fruc_options), then makes
    // `converter` a new converter with them; on an error it is left as it was.
    static Status create(int factor, const FrucOptions& options, FrameRateConverter& converter);
    ~FrameRateConverter();
    FrameRateConverter(FrameRateConverter&&) noexcept;
    FrameRateConverter& operator=(FrameRateConverter&&) noexcept;

    // Feeds the next rendered frame. Output frames then come out of receive() in order:
    // interpolation gives, for every frame after the first, the K-1 frames between it and its
    // predecessor followed by the frame itself; extrapolation gives the frame itself followed by
    // K-1 frames beyond it. Frames must have colour; depth, motion and cameras enable warping
    // (without them the output holds the last frame). A frame whose camera says Cut::Yes starts a
    // new shot: nothing is blended across it (Cut::Unknown: detected). Every output frame carries
    // colour, depth, motion (per output period), the camera and the UI layer; normals and ids are
    // not passed on. NaN and infinities are counted (counters().nonfinite) and repaired first:
    // colour as holes, depth NaN/-inf and motion as unknown; no output value is NaN or infinite but
    // background depth (+inf).
    Status send(const Frame& frame);
    // The same without copying the frame to keep it: its buffers become the converter's, and
    // `frame` gets back buffers of an earlier one (contents unspecified) for the caller to refill.
    // Non-finite values are repaired in place.
    Status send(Frame&& frame);
    // Ok with the next output frame in `out` (its buffers reused), or NeedMoreData: send the next
    // input first.
    Result receive(Frame& out);

    const FrucCounters& counters() const;
    // The region refinement surveyed as disagreeing for the last in-between frame made (1 on the
    // pixels of its tiles, 0 elsewhere; all 0 when none or refinement is off, and with a backend,
    // which surveys on its own), sized like it.
    void refine_region(Image<uint8_t>& mask) const;

private:
    Status send_frame(const Frame& given, Frame* owned);

    struct State;
    std::unique_ptr<State> state_;
};

}  // namespace reprise::warp
