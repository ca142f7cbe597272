#pragma once
// Motion refinement of an in-between frame (RefineOptions): where the two warped sides show one
// surface in different colours, optical flow (OpenCV's DIS) between the input frames, kept per
// pixel where its two sides agree better than the rendered motion's.
#include <memory>
#include <span>
#include <vector>

#include "reprise/core/gbuffer.hpp"
#include "reprise/warp/fruc.hpp"

namespace reprise::warp {

// One side of an in-between frame as warped: colour, depth and which pixels it covers.
struct WarpedSide {
    ImageView<const glm::vec4> color;
    ImageView<const float> depth;
    ImageView<const uint8_t> covered;
};

// A pixel takes the flow's colour where the 3x3 mean of its sides' error beats the rendered
// motion's by this.
inline constexpr float kRefineWinMargin = 0.01f;

// Pixels [x0, x1) x [y0, y1).
struct RefineBox {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
    int area() const { return width() * height(); }
    bool overlaps(const RefineBox& o) const {
        return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1;
    }
};

// The tiles refinement decides: `size` px squares (RefineOptions::tile, at least 4), x by y.
struct RefineTiles {
    int size = 16, x = 0, y = 0;
    static RefineTiles of(int width, int height, const RefineOptions& options);
    std::size_t count() const { return std::size_t(x) * std::size_t(y); }
};

class MotionRefiner {
public:
    MotionRefiner();
    ~MotionRefiner();
    // Surveys where the warped sides disagree at instant s between a and b and, where they do,
    // estimates flow there and keeps the better colour per pixel. False: nothing to apply.
    // `perceptual`: the colours of a, b and the sides are on FrucOptions::perceptual's scale.
    bool prepare(const GBufferView& a, const GBufferView& b, float s, const WarpedSide& side_a,
                 const WarpedSide& side_b, const RefineOptions& options, bool perceptual,
                 FrucCounters& counters);
    // Writes the colours the last prepare() kept over the blended frame (nothing after plan()).
    void apply(ImageView<glm::vec4> color) const;
    // Whether the colours of a and b themselves (a still pair) disagree anywhere as prepare()
    // would find.
    bool pictures_differ(const GBufferView& a, const GBufferView& b, const RefineOptions& options);
    // 1 on the pixels of the tiles the last survey found disagreeing, 0 elsewhere.
    void region(Image<uint8_t>& mask, int width, int height) const;
    void forget_region();

    // prepare()'s steps for a backend that surveys, evaluates and decides elsewhere (a GPU).
    // The survey's pixels: the odd columns of the image, in each tile's rows from its first + 1
    // every 2nd, where both sides cover one surface (depths within 2 %, or both +inf);
    // disagreeing where a channel's display values differ by more than the threshold. From those
    // counts per tile (row by row), the disagreeing tiles and the boxes the flow runs over (their
    // ring of tiles too with RefineOptions::neighbours, with the margin, merged, the most
    // disagreeing first within RefineOptions::max_flow_share, the others left empty), with
    // prepare()'s counters. No boxes: nothing to refine.
    const std::vector<RefineBox>& plan(int width, int height, std::span<const int> surveyed,
                                       std::span<const int> disagreeing,
                                       const RefineOptions& options, FrucCounters& counters);
    // Which box decides each tile (row by row; -1: none), after plan().
    std::span<const int> tile_boxes() const;
    // The flow over one box as prepare() estimates it: b(p) ~ a(p + flow), from the boxes' grey
    // pictures (grey(), box-sized) and `seed` (b's backward motion over the box; non-finite: 0).
    void flow(ImageView<const uint8_t> grey_b, ImageView<const uint8_t> grey_a,
              ImageView<const glm::vec2> seed, Image<glm::vec2>& flow);
    // The grey the flow sees: display luma (about sRGB) in 0..255, of linear light or of colour
    // on FrucOptions::perceptual's scale.
    static uint8_t grey(glm::vec4 color, bool perceptual = false);
    // The display value (about sRGB, within 1 %; NaN: 0) the survey compares, likewise.
    static float display(float value, bool perceptual);

private:
    struct State;
    std::unique_ptr<State> state_;
};

}  // namespace reprise::warp
