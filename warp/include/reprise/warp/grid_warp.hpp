#pragma once
// Adaptive-grid image warping (Didyk et al. 2010): a coarse grid refined at depth and motion
// discontinuities, its vertices moved along the motion, rasterised with a depth test.
#include <cstddef>
#include <memory>

#include "reprise/warp/splat.hpp"

namespace reprise::warp {

struct GridOptions {
    int cell = 32;                  // starting cell size in pixels: min_cell * 2^k, at most 64
    int min_cell = 2;               // smallest cell (1 or 2)
    float depth_threshold = 0.02f;  // split when max/min depth in a cell exceeds 1 + this
    float motion_threshold = 0.5f;  // split when motion inside a cell varies more (pixels)
};

struct GridStats {
    std::size_t cells = 0;    // cells drawn
    std::size_t covered = 0;  // covered output pixels
};

// Holds the cells and the scratch that it sizes once and reuses every frame.
//
// A cell splits while it holds a discontinuity: NaN/Inf motion or NaN/negative depth, background
// (+inf) beside geometry, depth ratio above 1 + depth_threshold or a motion range (per axis)
// above motion_threshold. Cells holding invalid pixels are not drawn. A cell corner takes the
// mean depth and motion of the 2x2 pixels around it when those are continuous by the same test
// (neighbouring cells then share the vertex and the grid stays closed), else those of the pixel
// of the cell nearest to it (the grid tears or stretches there). Each cell is drawn as two
// triangles split along the top-left to bottom-right diagonal, with depth interpolated linearly
// (background as a huge finite depth that loses against all geometry) and colour fetched
// bilinearly from the source at the interpolated source position. Cell edges are pushed out by
// 1/16 px so that T-junctions leave no hairline cracks. Cells with a vertex further than 2^20
// pixels away are dropped, and so is motion of 1e30 px or more. Same pixel coordinates in source
// and target, whose sizes may differ.
class GridWarper {
  public:
    GridStats warp(const Frame& source, float factor, const WarpTarget& target,
                   const GridOptions& options = {});
    // The single-threaded scalar reference.
    GridStats warp_reference(const Frame& source, float factor, const WarpTarget& target,
                             const GridOptions& options = {});

    GridWarper();
    ~GridWarper();
    GridWarper(GridWarper&&) noexcept;
    GridWarper& operator=(GridWarper&&) noexcept;

    struct State;  // cells and per-thread scratch (grid_internal.hpp)

  private:
    GridStats run(const Frame& source, float factor, const WarpTarget& target,
                  const GridOptions& options, bool threaded);
    std::unique_ptr<State> state_;
};

}  // namespace reprise::warp
