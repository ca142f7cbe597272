#pragma once
// The stages of the adaptive grid warp (grid_warp.cpp): growing the cells (grid_cells.cpp) and
// rasterising them into bands of target rows (grid_raster.cpp, band.hpp).
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "band.hpp"
#include "reprise/warp/grid_warp.hpp"

namespace reprise::warp::grid {

using Vertex = GridVertex;
using Cell = GridCell;
struct Row {  // the cells grown from one row of starting cells
    std::vector<Cell> cells;
    int y_lo = 0, y_hi = -1;  // target rows they may touch
};
// The smoothness test of a cell (grid_cells.cpp), row by row: the prediction of row v, at
// u = i * iu, is a[t] + u * b[t] in triangle t (0: upper right, where u >= v; 1: lower left).
struct RowFit {
    float v, iu;
    float wa[2], wb[2];      // inverse depth
    glm::vec2 ma[2], mb[2];  // motion
    bool background;         // the cell's kind
    float depth_tolerance, motion_limit;
};
struct CellFit {
    RowFit f;
    int x, y, n;          // the cell's first pixel and width
    float iv;             // v = j * iv on row j
    float w0, wv[2];      // a[t] = corner + v * gradient: inverse depth
    glm::vec2 m0, mv[2];  // motion
};

struct Scratch {  // one thread's: the tests of a row of starting cells, the grid points of a
                  // starting cell, a band of target rows
    std::vector<CellFit> fits;
    std::vector<uint8_t> fitting;
    std::vector<uint8_t> point_state;
    std::vector<Vertex> points;
    std::vector<glm::vec4> color;
    std::vector<float> depth;
    std::vector<glm::vec2> motion;
    std::vector<uint8_t> covered;
};

inline constexpr float kInf = std::numeric_limits<float>::infinity();
inline constexpr float kBackgroundDepth = 1e30f;  // background in the depth test
inline constexpr float kBackgroundFrom = kGridBackgroundFrom;
inline constexpr float kHugeMotion = 1e30f;  // motion this large (or NaN/Inf) is invalid
inline constexpr int kSubpixelBits = 8;      // target positions in 1/256 px
inline constexpr int kSubpixel = 1 << kSubpixelBits;
static_assert(kSubpixel == kGridSubpixel);
inline constexpr int kOverlap = kSubpixel / 16;  // edges pushed out by 1/16 px (grid_raster.cpp)
inline constexpr int kMaxCell = 64;

using Params = GridParameters;
inline Params make_params(const GridOptions& options, float factor) {
    return grid_parameters(options, factor);
}

// The first and last pixel whose centre (i + 0.5) lies at or after / at or before a fixed-point
// coordinate (arithmetic shifts round towards -inf).
inline int first_centre(int64_t v) {
    return int((v - kSubpixel / 2 + kSubpixel - 1) >> kSubpixelBits);
}
inline int last_centre(int64_t v) { return int((v - kSubpixel / 2) >> kSubpixelBits); }

// Replaces rows[r] by the cells grown from row r of starting cells, in a fixed order, for r in
// [begin, end). `simd` picks the vectorised smoothness test (same cells).
void build_rows(const GBufferView& source, const Params& params, int begin, int end, bool simd,
                Scratch& scratch, Row* rows);

// Sizes one worker's scratch for a source `source_width` pixels wide and bands of `band_rows`
// target rows (`motion`: with a motion band).
void size_scratch(Scratch& scratch, const Params& params, int source_width, int target_width,
                  int band_rows, bool motion);

// `simd` picks the vectorised span kernel (same result); it reads up to three depths past a
// span, so band rows must be padded (scratch_rows).
void draw_cell(ImageView<const glm::vec4> source, const Cell& cell, const Band& band, bool simd,
               bool bicubic);

}  // namespace reprise::warp::grid

namespace reprise::warp {
struct GridWarper::State {
    std::vector<grid::Row> rows;
    std::vector<grid::Scratch> scratch;
};
}  // namespace reprise::warp
