// reprise bench reproject — reverse reprojection (depth + id cache test, bilinear RGBA fetch)
// against cv::remap (INTER_LINEAR, CV_32FC4) on the same image with the same map.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

#include "args.hpp"
#include "bench.hpp"
#include "bench_report.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "reprise/warp/reproject.hpp"

namespace reprise::cli {

namespace {

Status bench_size(server::Renderer& renderer, const server::Scene& scene,
                  const server::CameraPath& path, int w, int h, int repetitions) {
    Frame prev, cur;
    const server::RenderSettings settings{.width = w, .height = h};
    REPRISE_TRY(renderer.render_frame(scene, path, 1, 30.0, settings, prev));
    REPRISE_TRY(renderer.render_frame(scene, path, 2, 30.0, settings, cur));

    // The lookup reproject makes, in OpenCV's convention (pixel centres at integers): p + motion
    // plus the jitter difference; no previous position -> far outside (border).
    const glm::vec2 shift = cur.camera.jitter - prev.camera.jitter;
    cv::Mat map_x(h, w, CV_32FC1), map_y(h, w, CV_32FC1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            glm::vec2 m = cur.motion(x, y);
            bool ok = std::isfinite(m.x) && std::isfinite(m.y);
            map_x.at<float>(y, x) = ok ? float(x) + shift.x + m.x : -1e6f;
            map_y.at<float>(y, x) = ok ? float(y) + shift.y + m.y : -1e6f;
        }
    cv::Mat fixed_xy, fixed_frac;
    cv::convertMaps(map_x, map_y, fixed_xy, fixed_frac, CV_16SC2);

    const cv::Mat src(h, w, CV_32FC4, prev.color.data());
    Image<glm::vec4> ours(w, h), reference(w, h), remapped(w, h), remapped16(w, h);
    cv::Mat dst(h, w, CV_32FC4, remapped.data()), dst16(h, w, CV_32FC4, remapped16.data());
    Image<uint8_t> hit(w, h);
    const warp::ConstPayload in = warp::payload_of(std::as_const(prev.color).view());
    warp::ReprojectCounts counts;

    Timing t_ours, t_remap, t_remap16, t_reference;
    auto run_ours = [&] {
        counts = warp::reproject(cur, prev, in, warp::payload_of(ours.view()), hit.view());
    };
    auto run_remap = [&] {
        cv::remap(src, dst, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    };
    auto run_remap16 = [&] {
        cv::remap(src, dst16, fixed_xy, fixed_frac, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    };
    run_ours();  // warm-up: page in the outputs, start the pools
    run_remap();
    run_remap16();
    for (int i = 0; i < repetitions;
         ++i) {  // interleaved, so that load on the machine hits all alike
        time_once(t_ours, run_ours);
        time_once(t_remap, run_remap);
        time_once(t_remap16, run_remap16);
        std::fprintf(stderr, "\r[bench] %dx%d %d/%d", w, h, i + 1, repetitions);
    }
    for (int i = 0; i < std::min(repetitions, 3); ++i)
        time_once(t_reference, [&] {
            warp::reproject_reference(cur, prev, in, warp::payload_of(reference.view()), {});
        });
    std::fprintf(stderr, "\r%40s\r", "");

    // Where we hit and the lookup is at least half a pixel inside (OpenCV blends the border
    // colour in there, we clamp), the two agree up to OpenCV's 1/32-pixel weights.
    double max_diff = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float u = map_x.at<float>(y, x), v = map_y.at<float>(y, x);
            if (!hit(x, y) || !(u >= 0 && v >= 0 && u <= w - 1 && v <= h - 1)) continue;
            for (int c = 0; c < 4; ++c)
                max_diff = std::max(max_diff, double(std::abs(ours(x, y)[c] - remapped(x, y)[c])));
        }

    std::printf("%-10s %5.1f%% %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %7.2fx %7.2fx %9.1f %9.4f\n",
                (std::to_string(w) + "x" + std::to_string(h)).c_str(),
                100.0 * double(counts.hits) / double(std::size_t(w) * h), t_ours.best(),
                t_ours.median(), t_remap.best(), t_remap.median(), t_remap16.best(),
                t_remap16.median(), t_ours.best() / t_remap.best(),
                t_ours.median() / t_remap.median(), t_reference.median(), max_diff);
    return {};
}

}  // namespace

Status bench_reproject(const BenchOptions& options) {
    BenchScene bench;
    REPRISE_TRY(open_bench_scene(options.scene, bench));
    auto& [scene, path, renderer] = bench;
    cv::setNumThreads(thread_count());
    std::printf(
        "reverse reprojection (RGBA float payload, depth + id test) vs cv::remap "
        "(INTER_LINEAR, CV_32FC4, float maps; remap16: CV_16SC2 fixed-point maps)\n"
        "scene %s, frames 1 -> 2, %d threads (reprise) / %d (OpenCV), best and median of %d, ms\n",
        options.scene.c_str(), thread_count(), cv::getNumThreads(), options.frames);
    std::printf("ratio = ours / remap (float maps); max diff: largest where we hit (interior)\n");
    std::printf("%-10s %6s %8s %8s %8s %8s %8s %8s %8s %8s %9s %9s\n", "size", "hits", "ours",
                "ours", "remap", "remap", "remap16", "remap16", "ratio", "ratio", "reference",
                "max diff");
    std::printf("%-10s %6s %8s %8s %8s %8s %8s %8s %8s %8s %9s %9s\n", "", "", "best", "median",
                "best", "median", "best", "median", "best", "median", "1 thread", "vs remap");
    std::size_t start = 0;
    while (start <= options.sizes.size()) {
        std::size_t end = options.sizes.find(',', start);
        if (end == std::string::npos) end = options.sizes.size();
        int w = 0, h = 0;
        REPRISE_TRY(parse_size(options.sizes.substr(start, end - start), w, h));
        REPRISE_TRY(bench_size(*renderer, scene, path, w, h, options.frames));
        start = end + 1;
    }
    return {};
}

}  // namespace reprise::cli
