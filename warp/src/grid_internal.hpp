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

struct Vertex {
    int32_t x, y;  // target position, 1/256 pixel
    float sx, sy;  // source position, pixels
    float z;       // depth (background: a huge finite stand-in)
    float mx, my;  // motion
};
struct Cell {
    Vertex v[4];  // top-left, top-right, bottom-right, bottom-left
};
struct Row {  // the cells grown from one row of starting cells
    std::vector<Cell> cells;
    int y_lo = 0, y_hi = -1;  // target rows they may touch
};
struct Scratch {  // one thread's: ranges of a row of starting cells, the grid points of a
                  // starting cell, a band of target rows
    std::vector<float> zmin, zmax;
    std::vector<glm::vec2> m0, m1;
    std::vector<uint8_t> point_state;
    std::vector<Vertex> points;
    std::vector<glm::vec4> color;
    std::vector<float> depth;
    std::vector<glm::vec2> motion;
    std::vector<uint8_t> covered;
};

inline constexpr float kInf = std::numeric_limits<float>::infinity();
inline constexpr float kBackgroundDepth = 1e30f;  // background in the depth test
inline constexpr float kBackgroundFrom = 1e29f;   // depths from here on count as background
inline constexpr float kHugeMotion = 1e30f;       // motion this large (or NaN/Inf) is invalid
inline constexpr int kSubpixelBits = 8;           // target positions in 1/256 px
inline constexpr int kSubpixel = 1 << kSubpixelBits;
inline constexpr int kOverlap = kSubpixel / 16;  // edges pushed out by 1/16 px (grid_raster.cpp)
inline constexpr int kMaxCell = 64;

struct Params {
    float z_ratio;  // 1 + depth_threshold
    float motion_threshold;
    int cell, min_cell;
    float factor;
};
Params make_params(const GridOptions& options, float factor);

// The first and last pixel whose centre (i + 0.5) lies at or after / at or before a fixed-point
// coordinate (arithmetic shifts round towards -inf).
inline int first_centre(int64_t v) {
    return int((v - kSubpixel / 2 + kSubpixel - 1) >> kSubpixelBits);
}
inline int last_centre(int64_t v) {
    return int((v - kSubpixel / 2) >> kSubpixelBits);
}

// Replaces rows[r] by the cells grown from row r of starting cells, in a fixed order, for r in
// [begin, end). `simd` picks the vectorised min/max pyramid (same cells).
void build_rows(const Frame& source, const Params& params, int begin, int end, bool simd,
                Scratch& scratch, Row* rows);

// `simd` picks the vectorised span kernel (same result); it reads up to three depths past a
// span, so band rows must be padded (scratch_rows).
void draw_cell(ImageView<const glm::vec4> source, const Cell& cell, const Band& band, bool simd);

}  // namespace reprise::warp::grid

namespace reprise::warp {
struct GridWarper::State {
    std::vector<grid::Row> rows;
    std::vector<grid::Scratch> scratch;
};
}  // namespace reprise::warp
