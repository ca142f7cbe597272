// Adaptive-grid warping: cells grown row by row of starting cells (grid_cells.cpp), then drawn
// band by band of target rows (grid_raster.cpp). Every band visits the cells in the same order,
// so the threaded result equals the single-band reference.
#include "reprise/warp/grid_warp.hpp"

#include <algorithm>
#include <atomic>
#include <limits>

#include "grid_internal.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::warp {

namespace {

constexpr int kBandRows = 8;  // a band's scratch (29 bytes a pixel) stays in a core's cache

void check(const GBufferView& source, const WarpTarget& t) {
    check_warp_inputs(source, t);
    // The vector raster keeps source offsets (in pixels) in 32-bit lanes.
    REPRISE_ASSERT(source.color.empty() || double(source.width()) * source.height() <
                                               double(std::numeric_limits<int>::max()));
}

}  // namespace

GridWarper::GridWarper() : state_(std::make_unique<State>()) {}
GridWarper::~GridWarper() = default;
GridWarper::GridWarper(GridWarper&&) noexcept = default;
GridWarper& GridWarper::operator=(GridWarper&&) noexcept = default;

int GridWarper::build(const GBufferView& source, float factor, const GridOptions& options,
                      bool threaded, int bands, int target_width, bool motion) {
    const grid::Params params = grid::make_params(options, factor);
    const int top_rows =
        source.color.empty() ? 0 : (source.height() + params.cell - 1) / params.cell;
    if (!state_) state_ = std::make_unique<State>();  // moved from
    State& st = *state_;
    if (int(st.rows.size()) < top_rows) st.rows.resize(std::size_t(top_rows));
    const int workers =
        threaded ? std::max(1, std::min(thread_count(), std::max(top_rows, bands))) : 1;
    if (int(st.scratch.size()) < workers) st.scratch.resize(std::size_t(workers));
    // Sized here, not on first use: which worker gets work depends on scheduling, and a worker
    // that first gets some in a later frame must not allocate then.
    for (int k = 0; k < workers; ++k)
        grid::size_scratch(st.scratch[std::size_t(k)], params, source.width(), target_width,
                           kBandRows, motion);
    if (threaded) {
        std::atomic<int> next{0};
        parallel_for(
            0, workers,
            [&](int a, int b) {
                for (int k = a; k < b; ++k)
                    for (int r = next++; r < top_rows; r = next++)
                        grid::build_rows(source, params, r, r + 1, true, st.scratch[std::size_t(k)],
                                         st.rows.data());
            },
            1);
    } else {
        grid::build_rows(source, params, 0, top_rows, false, st.scratch[0], st.rows.data());
    }
    return top_rows;
}

void GridWarper::cells(const GBufferView& source, float factor, const GridOptions& options,
                       std::vector<GridCell>& cells) {
    REPRISE_ASSERT(source.depth.width == source.width() && source.depth.height == source.height());
    REPRISE_ASSERT(source.motion.width == source.width() &&
                   source.motion.height == source.height());
    cells.clear();
    const int top_rows = build(source, factor, options, true, 1, 1, false);
    for (int r = 0; r < top_rows; ++r) {
        const grid::Row& row = state_->rows[std::size_t(r)];
        cells.insert(cells.end(), row.cells.begin(), row.cells.end());
    }
}

GridStats GridWarper::run(const GBufferView& source, float factor, const WarpTarget& target,
                          const GridOptions& options, bool threaded) {
    check(source, target);
    GridStats stats;
    if (target.color.empty()) return stats;
    const int height = target.color.height, bands = (height + kBandRows - 1) / kBandRows;
    const int top_rows =
        build(source, factor, options, threaded, bands, target.color.width, !target.motion.empty());
    State& st = *state_;
    const int workers =
        threaded ? std::max(1, std::min(thread_count(), std::max(top_rows, bands))) : 1;
    for (int r = 0; r < top_rows; ++r) stats.cells += st.rows[std::size_t(r)].cells.size();

    const ImageView<const glm::vec4> color = source.color;
    auto draw = [&](const Band& band, bool simd) {
        clear_band(band);
        const int y_end = band.y0 + band.view.color.height;
        for (int r = 0; r < top_rows; ++r) {
            const grid::Row& row = st.rows[std::size_t(r)];
            if (row.y_hi < band.y0 || row.y_lo >= y_end) continue;
            for (const grid::Cell& c : row.cells)
                grid::draw_cell(color, c, band, simd, options.bicubic);
        }
    };
    if (!threaded) {
        const Band whole{target, 0};
        draw(whole, false);
        stats.covered = finish_band(whole, grid::kBackgroundFrom, &stats.nonfinite, true);
        return stats;
    }

    const int width = target.color.width;
    std::atomic<int> next{0};
    std::atomic<std::size_t> covered{0}, nonfinite{0};
    parallel_for(
        0, workers,
        [&](int a, int b) {
            for (int k = a; k < b; ++k) {
                grid::Scratch& scratch = st.scratch[std::size_t(k)];
                std::size_t n = 0, bad = 0;
                for (int i = next++; i < bands; i = next++) {
                    const int y0 = i * kBandRows, rows = std::min(kBandRows, height - y0);
                    const Band band{
                        {scratch_rows(scratch.color, width, rows),
                         scratch_rows(scratch.depth, width, rows),
                         target.motion.empty() ? ImageView<glm::vec2>{}
                                               : scratch_rows(scratch.motion, width, rows),
                         scratch_rows(scratch.covered, width, rows)},
                        y0};
                    draw(band, true);
                    n += copy_band(band, target, grid::kBackgroundFrom, &bad, true);
                }
                covered += n;
                nonfinite += bad;
            }
        },
        1);
    stats.covered = covered;
    stats.nonfinite = nonfinite;
    return stats;
}

GridStats GridWarper::warp(const GBufferView& source, float factor, const WarpTarget& target,
                           const GridOptions& options) {
    return run(source, factor, target, options, true);
}

GridStats GridWarper::warp_reference(const GBufferView& source, float factor,
                                     const WarpTarget& target, const GridOptions& options) {
    return run(source, factor, target, options, false);
}

}  // namespace reprise::warp
