// reprise bench paths — whole made frames (interpolated with the grid and the reverse warp,
// extrapolated, the second eye) against cv::remap of the same frame, timed interleaved in one run.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "args.hpp"
#include "bench.hpp"
#include "bench_report.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/stereo/rig.hpp"
#include "reprise/stereo/synthesize.hpp"
#include "reprise/warp/fruc.hpp"

namespace reprise::cli {

namespace {

struct Converter {
    const char* name;
    warp::FrucOptions options;
    warp::FrameRateConverter converter;
    Frame in, out;
    Timing times;
};

Status bench_paths_size(const BenchScene& bench, int w, int h, int timed,
                        const std::string& backend) {
    // timed + 2 consecutive frames: the converters are fed in order, the first two untimed.
    std::vector<Frame> frames(std::size_t(timed + 2));
    for (int i = 0; i < timed + 2; ++i) {
        REPRISE_TRY(bench.renderer->render_frame(bench.scene, bench.path, 10 + i, 30.0,
                                                 {.width = w, .height = h},
                                                 frames[std::size_t(i)]));
        std::fprintf(stderr, "\r[bench] rendering %d/%d", i + 1, timed + 2);
    }
    std::fprintf(stderr, "\r%40s\r", "");

    using warp::FrucMode, warp::WarpMethod, warp::FillMethod;
    // The default (bicubic grid, refinement on), then what each of those costs.
    const warp::RefineOptions off{.enabled = false};
    const warp::GridOptions bilinear{.bicubic = false};
    Converter converters[] = {
        {"interpolate grid+pullpush", {}},
        {"interpolate grid, refine off", {.refine = off}},
        {"interpolate grid-bilinear, refine off", {.grid = bilinear, .refine = off}},
        {"interpolate reverse+pullpush", {.warp = WarpMethod::Reverse}},
        {"interpolate reverse, refine off", {.warp = WarpMethod::Reverse, .refine = off}},
        {"extrapolate grid+pullpush", {.mode = FrucMode::Extrapolate}},
        {"extrapolate grid-bilinear", {.mode = FrucMode::Extrapolate, .grid = bilinear}},
    };
    for (Converter& c : converters)
        REPRISE_TRY(warp::FrameRateConverter::create(2, c.options, c.converter));
    stereo::StereoSynthesizer synthesizer;
    Frame eye;
    Timing stereo_times, remap_times, copy_times;
    Image<glm::vec4> copied(w, h);
    cv::Mat map_x(h, w, CV_32FC1), map_y(h, w, CV_32FC1);
    Image<glm::vec4> remapped(w, h);
    cv::Mat dst(h, w, CV_32FC4, remapped.data());

    for (int i = 0; i < timed + 2; ++i) {
        const Frame& f = frames[std::size_t(i)];
        const bool timing = i >= 2;
        for (Converter& c : converters) {
            Status sent;
            c.in = f;  // untimed: the caller's frame, handed over without a copy
            auto run = [&] {
                sent = c.converter.send(std::move(c.in));
                while (c.converter.receive(c.out)) {
                }
            };
            if (timing)
                time_once(c.times, run);
            else
                run();
            REPRISE_TRY(sent);
        }
        const stereo::EyeCameras eyes = stereo::eye_cameras(f.camera, {}, stereo::Anchor::Left);
        auto synthesize = [&] { synthesizer.synthesize(f, eyes.right, eye); };
        if (timing)
            time_once(stereo_times, synthesize);
        else
            synthesize();
        // The peer: cv::remap of this frame's colour along its motion (bilinear, float maps).
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const glm::vec2 m = f.motion(x, y);
                const bool ok = std::isfinite(m.x) && std::isfinite(m.y);
                map_x.at<float>(y, x) = ok ? float(x) + 0.5f * m.x : -1e6f;
                map_y.at<float>(y, x) = ok ? float(y) + 0.5f * m.y : -1e6f;
            }
        const cv::Mat src(h, w, CV_32FC4, const_cast<glm::vec4*>(f.color.data()));
        auto remap = [&] {
            cv::remap(src, dst, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
        };
        if (timing)
            time_once(remap_times, remap);
        else
            remap();
        // The memory floor: the colour copied once, rows in parallel (what one pass costs).
        auto copy = [&] {
            parallel_for(0, h, [&](int y0, int y1) {
                std::memcpy(&copied(0, y0), &f.color(0, y0),
                            std::size_t(y1 - y0) * std::size_t(w) * sizeof(glm::vec4));
            });
        };
        if (timing)
            time_once(copy_times, copy);
        else
            copy();
        std::fprintf(stderr, "\r[bench] %dx%d %d/%d", w, h, i + 1, timed + 2);
    }
    std::fprintf(stderr, "\r%40s\r", "");

    const std::string size = std::to_string(w) + "x" + std::to_string(h);
    auto row = [&](const char* name, const Timing& t, double refine_ms) {
        std::printf("%-10s %-38s %9.2f %9.2f %8.2fx %8.2fx %9.2f\n", size.c_str(), name, t.best(),
                    t.median(), t.best() / remap_times.best(), t.median() / remap_times.median(),
                    refine_ms);
    };
    for (const Converter& c : converters) {
        const warp::FrucCounters& n = c.converter.counters();
        row(c.name, c.times, n.outputs ? n.refine_ms / double(n.outputs) : 0.0);
    }
    row("stereo eye grid+pullpush", stereo_times, 0.0);
    row("cv::remap (peer)", remap_times, 0.0);
    row("colour copy (memory floor)", copy_times, 0.0);
    if (backend == "gles") REPRISE_TRY(bench_gles_stages(frames, size));
    return {};
}

}  // namespace

Status bench_paths(const BenchOptions& options) {
    if (options.backend != "cpu" && options.backend != "gles")
        return Status::error("bench paths: --backend '" + options.backend +
                             "': expected cpu or gles");
    BenchScene bench;
    REPRISE_TRY(open_bench_scene(options.scene, bench));
    cv::setNumThreads(thread_count());
    std::printf(
        "whole made frames vs cv::remap (INTER_LINEAR, CV_32FC4, float maps) of the same frame, "
        "interleaved\nscene %s from frame 10, %d timed frames, %d threads (reprise) / %d (OpenCV); "
        "fruc x2: one send(Frame&&) + receive() per frame (the made frame, the input passed "
        "through, "
        "the shot-change test; refine ms: its mean in motion refinement); stereo: the right eye "
        "from the left (ipd 0.064)\n",
        options.scene.c_str(), options.frames, thread_count(), cv::getNumThreads());
    std::printf("%-10s %-38s %9s %9s %9s %9s %9s\n", "size", "path", "best ms", "median ms",
                "best/remap", "med/remap", "refine ms");
    for (const std::string& size : split_list(options.sizes)) {
        int w = 0, h = 0;
        REPRISE_TRY(parse_size(size, w, h));
        REPRISE_TRY(bench_paths_size(bench, w, h, options.frames, options.backend));
    }
    return {};
}

}  // namespace reprise::cli
