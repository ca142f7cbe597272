// reprise bench grid — forward splatting (1 and 2x2 footprints) and the adaptive grid warp (with
// and without the motion output, and with the bicubic colour fetch), extrapolating half a frame,
// against cv::remap (INTER_LINEAR, CV_32FC4) of the same image with a map made from the same
// motion.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "args.hpp"
#include "bench.hpp"
#include "bench_report.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "reprise/warp/grid_warp.hpp"
#include "reprise/warp/splat.hpp"

namespace reprise::cli {

namespace {

constexpr float kFactor = -0.5f;  // extrapolation by half a frame
constexpr double kGridBudgetMs = 8.0;

struct Target {
    Image<glm::vec4> color;
    Image<float> depth;
    Image<glm::vec2> motion;
    Image<uint8_t> covered;
    Target(int w, int h) : color(w, h), depth(w, h), motion(w, h), covered(w, h) {}
    warp::WarpTarget view() { return {color.view(), depth.view(), motion.view(), covered.view()}; }
};

Status bench_size(server::Renderer& renderer, const server::Scene& scene,
                  const server::CameraPath& path, int w, int h, int repetitions, bool& met_budget) {
    Frame frame;
    REPRISE_TRY(renderer.render_frame(scene, path, 2, 30.0, {.width = w, .height = h}, frame));

    // The peer's gather: target pixel q reads the source at q - factor * motion(q) (OpenCV puts
    // pixel centres at integers).
    cv::Mat map_x(h, w, CV_32FC1), map_y(h, w, CV_32FC1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::vec2 m = frame.motion(x, y);
            const bool ok = std::isfinite(m.x) && std::isfinite(m.y);
            map_x.at<float>(y, x) = ok ? float(x) - kFactor * m.x : -1e6f;
            map_y.at<float>(y, x) = ok ? float(y) - kFactor * m.y : -1e6f;
        }
    const cv::Mat src(h, w, CV_32FC4, frame.color.data());
    Image<glm::vec4> remapped(w, h);
    cv::Mat dst(h, w, CV_32FC4, remapped.data());

    Target t1(w, h), t2(w, h), tg(w, h), tn(w, h), tc(w, h), tr(w, h);
    warp::WarpTarget no_motion = tn.view();  // the grid warp without the motion output
    no_motion.motion = {};
    warp::GridWarper warper;
    std::size_t covered1 = 0, covered2 = 0;
    warp::GridStats grid;
    Timing splat1, splat2, grid_ms, grid_nm_ms, grid_cubic_ms, cells_ms, remap_ms, reference_ms;
    std::vector<warp::GridCell> cells;
    auto run_splat1 = [&] { covered1 = warp::splat(frame, kFactor, t1.view(), {.footprint = 1}); };
    auto run_splat2 = [&] { covered2 = warp::splat(frame, kFactor, t2.view(), {.footprint = 2}); };
    auto run_grid = [&] { grid = warper.warp(frame, kFactor, tg.view()); };
    auto run_grid_nm = [&] { (void)warper.warp(frame, kFactor, no_motion); };
    auto run_grid_cubic = [&] { (void)warper.warp(frame, kFactor, tc.view(), {.bicubic = true}); };
    auto run_cells = [&] { warper.cells(frame, kFactor, {}, cells); };
    auto run_remap = [&] {
        cv::remap(src, dst, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    };
    run_splat1();  // warm-up: page in the outputs, start the pools, size the scratch
    run_splat2();
    run_grid();
    run_remap();
    for (int i = 0; i < repetitions;
         ++i) {  // interleaved, so that load on the machine hits all alike
        time_once(splat1, run_splat1);
        time_once(splat2, run_splat2);
        time_once(grid_ms, run_grid);
        time_once(grid_nm_ms, run_grid_nm);
        time_once(grid_cubic_ms, run_grid_cubic);
        time_once(cells_ms, run_cells);
        time_once(remap_ms, run_remap);
        std::fprintf(stderr, "\r[bench] %dx%d %d/%d", w, h, i + 1, repetitions);
    }
    for (int i = 0; i < std::min(repetitions, 3); ++i)
        time_once(reference_ms, [&] { (void)warper.warp_reference(frame, kFactor, tr.view()); });
    std::fprintf(stderr, "\r%40s\r", "");

    const double pixels = double(w) * h, remap = remap_ms.median();
    const std::string size = std::to_string(w) + "x" + std::to_string(h);
    std::printf("%-10s %-8s %8.2f %7.2fx %8s %8.2f%%\n", size.c_str(), "splat1", splat1.median(),
                splat1.median() / remap, "", 100.0 * double(covered1) / pixels);
    std::printf("%-10s %-8s %8.2f %7.2fx %8s %8.2f%%\n", "", "splat2", splat2.median(),
                splat2.median() / remap, "", 100.0 * double(covered2) / pixels);
    std::printf("%-10s %-8s %8.2f %7.2fx %8zu %8.2f%%  (reference, 1 thread: %.2f ms)\n", "",
                "grid", grid_ms.median(), grid_ms.median() / remap, grid.cells,
                100.0 * double(grid.covered) / pixels, reference_ms.median());
    std::printf("%-10s %-8s %8.2f %7.2fx %8s %8s  (no motion output)\n", "", "grid-nm",
                grid_nm_ms.median(), grid_nm_ms.median() / remap, "", "");
    std::printf("%-10s %-8s %8.2f %7.2fx %8s %8s  (bicubic colour, as fruc's default)\n", "",
                "grid-cub", grid_cubic_ms.median(), grid_cubic_ms.median() / remap, "", "");
    std::printf(
        "%-10s %-8s %8.2f %7.2fx %8zu %8s  (the cells alone: the GPU's grid leaves them "
        "on the CPU)\n",
        "", "cells", cells_ms.median(), cells_ms.median() / remap, cells.size(), "");
    std::printf("%-10s %-8s %8.2f %7.2fx\n", "", "remap", remap, 1.0);
    if (w == 1920 && h == 1080) met_budget = grid_ms.median() <= kGridBudgetMs;
    return {};
}

}  // namespace

Status bench_grid(const BenchOptions& options) {
    BenchScene bench;
    REPRISE_TRY(open_bench_scene(options.scene, bench));
    auto& [scene, path, renderer] = bench;
    cv::setNumThreads(thread_count());
    std::printf(
        "forward warps extrapolating by %.1f frame (RGBA float, depth, motion, coverage) vs "
        "cv::remap (INTER_LINEAR, CV_32FC4, float maps)\n"
        "scene %s, frame 2, %d threads (reprise) / %d (OpenCV), median of %d, ms\n",
        -kFactor, options.scene.c_str(), thread_count(), cv::getNumThreads(), options.frames);
    std::printf("%-10s %-8s %8s %8s %8s %9s\n", "size", "method", "ms", "/remap", "cells",
                "covered");
    bool measured = false, met_budget = false;
    std::size_t start = 0;
    while (start <= options.sizes.size()) {
        std::size_t end = options.sizes.find(',', start);
        if (end == std::string::npos) end = options.sizes.size();
        int w = 0, h = 0;
        REPRISE_TRY(parse_size(options.sizes.substr(start, end - start), w, h));
        REPRISE_TRY(bench_size(*renderer, scene, path, w, h, options.frames, met_budget));
        measured = measured || (w == 1920 && h == 1080);
        start = end + 1;
    }
    if (measured)
        std::printf("grid warp at 1920x1080 %s the %.0f ms budget\n",
                    met_budget ? "meets" : "misses", kGridBudgetMs);
    return {};
}

}  // namespace reprise::cli
