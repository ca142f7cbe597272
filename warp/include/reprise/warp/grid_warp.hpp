#pragma once
// Adaptive-grid image warping (Didyk et al. 2010): a coarse grid refined at depth and motion
// discontinuities, its vertices moved along the motion, rasterised with a depth test.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "reprise/warp/splat.hpp"

namespace reprise::warp {

struct GridOptions {
    int cell = 32;  // starting cell size in pixels: min_cell * 2^k, at most 64
    // Smallest cell, 1 or 2. One-pixel cells keep a silhouette's last column where the
    // background slides under it; two-pixel cells draw it as a stretch into the background.
    int min_cell = 1;
    // How far a pixel may depart from what its cell's corner pixels predict (interpolated over
    // the two triangles the cell is drawn as) before the cell splits:
    // inverse depth (affine in screen space on a plane), relative: |1 - predicted(1/z) * z|;
    float depth_threshold = 0.01f;  // at most 0.5
    // motion in target pixels, i.e. |factor| * |motion - predicted motion| on either axis.
    float motion_threshold = 0.25f;
    // Colour by a Catmull-Rom (bicubic) fetch at the interpolated source position instead of a
    // bilinear one: sharper, as the reverse warp's refetch.
    bool bicubic = false;
    // An edge triangle (a smallest cell across a depth edge) whose area grows by more than this
    // many px^2 from source to target is stretched over a disocclusion: its pixels more than a
    // pixel from either end of the stretch are marked kCoveredStretched, and an in-between frame
    // takes the other side there where that side saw the surface (+inf: none marked). 0.5 px^2
    // measured best of 0, 0.5, 1, 2, 3 (docs/benchmarks.md).
    float stretched_area = 0.5f;
};

// A cell as the raster draws it (GridWarper::cells: the GPU's mesh). Target positions are in
// 1/kGridSubpixel px; depth at or beyond kGridBackgroundFrom is background (+inf once drawn).
inline constexpr int kGridSubpixel = 256;
inline constexpr float kGridBackgroundFrom = 1e29f;
struct GridVertex {
    int32_t x, y;  // target position, 1/kGridSubpixel px
    float sx, sy;  // source position, pixels
    float z;       // depth (background: a huge finite stand-in)
    float mx, my;  // motion
};
struct GridCell {
    GridVertex v[4];  // top-left, top-right, bottom-right, bottom-left
    // Passed the smoothness test: depth is interpolated as 1/z (perspective-correct). Else (the
    // smallest cells across an edge) linearly, so that background never pulls geometry along.
    bool perspective;
    // Per triangle (v0 v1 v2, v0 v2 v3), what `covered` becomes where it is drawn: 1, or
    // kCoveredStretched for an edge triangle across a depth edge stretched over a disocclusion.
    uint8_t coverage[2];
};

// The thresholds a cell's growth uses, from GridOptions and the warp's factor (shared with the
// GPU's cell growth, gpu/src/grid_cells.cpp).
struct GridParameters {
    float depth_tolerance;  // depth_threshold: allowed |1 - predicted(1/z) * z|
    float motion_limit;     // motion_threshold / |factor|: allowed motion error, source pixels
    float vertex_z_ratio;   // 1 + 2 depth_tolerance: 2x2 pixels that share a vertex
    float vertex_motion;    // 2 motion_limit: their motion range
    float stretched_area;   // stretched_area: px^2 an edge triangle grows by to be stretched
    int cell, min_cell;     // the starting and the smallest cell, pixels
    float factor;
};
GridParameters grid_parameters(const GridOptions& options, float factor);

struct GridStats {
    std::size_t cells = 0;      // cells drawn
    std::size_t covered = 0;    // covered output pixels (stretched ones too)
    std::size_t nonfinite = 0;  // ... whose colour has a NaN or infinite channel
};

// Holds the cells and the scratch that it sizes once and reuses every frame.
//
// A cell splits (down to min_cell) while it holds invalid pixels (NaN/Inf motion, NaN/negative
// depth), background (+inf) beside geometry, or a pixel whose motion or inverse depth departs
// from the interpolation of the cell's four corner pixels (over the two triangles it is drawn
// as) by more than the thresholds above. Every pixel is tested, so a pole one pixel wide inside
// a cell refines it. A plane seen in perspective (a tilted ground) has affine 1/z and nearly
// affine motion, so it keeps big cells, while depth and motion edges, silhouettes and curved
// surfaces refine. Smallest cells holding invalid pixels are not drawn.
// A cell corner takes the mean depth and motion of the 2x2 pixels around it when those are
// continuous (one kind, depth ratio within 1 + 2 depth_threshold, motion range within twice
// the motion threshold: neighbouring cells then share the vertex and the grid stays closed),
// else those of the pixel of the cell nearest to it (the grid tears or stretches there). Each
// cell is drawn as two triangles split along the top-left to bottom-right diagonal; depth is
// interpolated perspective-correctly (1/z linearly) in cells that passed the test, linearly in
// the smallest cells that hold an edge by the vertex test (background there as a huge finite
// depth that loses against all geometry); colour is fetched bilinearly from the source at the
// interpolated source position (or bicubically, `bicubic`). Cell edges are pushed out by 1/16 px so
// that T-junctions leave no hairline cracks. Cells with a vertex further than 2^20 pixels away are
// dropped, and so is motion of 1e30 px or more. Same pixel coordinates in source and target, whose
// sizes may differ.
class GridWarper {
public:
    GridStats warp(const GBufferView& source, float factor, const WarpTarget& target,
                   const GridOptions& options = {});
    // The cells warp() would draw, in its drawing order (later cells lose depth ties), into
    // `cells`; the GPU draws them (gpu/src/grid.cpp).
    void cells(const GBufferView& source, float factor, const GridOptions& options,
               std::vector<GridCell>& cells);
    // The single-threaded scalar reference.
    GridStats warp_reference(const GBufferView& source, float factor, const WarpTarget& target,
                             const GridOptions& options = {});

    GridWarper();
    ~GridWarper();
    GridWarper(GridWarper&&) noexcept;
    GridWarper& operator=(GridWarper&&) noexcept;

    struct State;  // cells and per-thread scratch (grid_internal.hpp)

private:
    // Grows the cells into the state's rows, its scratch sized for `bands` bands of a target
    // `target_width` wide; returns how many rows of starting cells.
    int build(const GBufferView& source, float factor, const GridOptions& options, bool threaded,
              int bands, int target_width, bool motion);
    GridStats run(const GBufferView& source, float factor, const WarpTarget& target,
                  const GridOptions& options, bool threaded);
    std::unique_ptr<State> state_;
};

}  // namespace reprise::warp
