#pragma once
// Frame-rate upconversion: K output frames per rendered frame, by interpolation between the last
// two frames or by extrapolation from the last one alone (no added latency).
#include <cstddef>
#include <memory>

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
};
enum class FillMethod { None, PullPush, Andreev };

struct FrucOptions {
    FrucMode mode = FrucMode::Interpolate;
    WarpMethod warp = WarpMethod::Grid;
    FillMethod fill = FillMethod::PullPush;
    // The grid fetches colour bicubically: on anti-aliased renders it measured 0.6-1.1 dB above the
    // bilinear fetch (docs/benchmarks.md). The stereo eye keeps GridOptions' bilinear default.
    GridOptions grid{.bicubic = true};
    SplatOptions splat;
    // A new frame whose reverse reprojection into the previous one misses on more than this
    // fraction of pixels, or whose hits differ in mean display colour by more than cut_color,
    // starts a new shot: the history is dropped, nothing is blended across it.
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
};

// What was done and what was left out because the frame did not need it.
struct FrucCounters {
    std::size_t inputs = 0;
    std::size_t outputs = 0;        // frames made (inputs passed through are not counted)
    std::size_t copied_still = 0;   // zero motion: exact copy, nothing warped
    std::size_t fills = 0;          // frames whose holes were filled
    std::size_t fills_skipped = 0;  // no holes: no fill
    std::size_t hole_pixels = 0;
    std::size_t dynamic_layers = 0;   // extrapolation: frames with moving objects drawn on top
    std::size_t dynamic_skipped = 0;  // no dynamic pixels: no dynamic layer
    std::size_t cuts = 0;             // shot changes detected
    std::size_t grid_cells = 0;       // adaptive-grid cells drawn
    std::size_t true_motion = 0;      // in-between frames whose sides followed the true motion
    std::size_t linear_motion = 0;    // ... that did not need it: a sparse survey found it linear
};

// The camera between or beyond two instants: view matrices blended as rigid motions (rotation
// slerp, translation lerp, s may exceed 1), the projection taken from `b`.
Camera camera_between(const Camera& a, const Camera& b, float s);

class FrameRateConverter {
public:
    FrameRateConverter(int factor, const FrucOptions& options);
    ~FrameRateConverter();

    // Feeds the next rendered frame. Output frames then come out of receive() in order:
    // interpolation gives, for every frame after the first, the K-1 frames between it and its
    // predecessor followed by the frame itself; extrapolation gives the frame itself followed by
    // K-1 frames beyond it. Frames must have colour; depth, motion and cameras enable warping
    // (without them the output holds the last frame).
    Status send(const Frame& frame);
    // Takes the next output frame; false when the converter needs the next input.
    bool receive(Frame& out);

    const FrucCounters& counters() const;

private:
    struct State;
    std::unique_ptr<State> state_;
};

}  // namespace reprise::warp
