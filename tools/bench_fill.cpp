// reprise bench fill — pull-push (plain and depth-aware) and Andreev inpainting against OpenCV's
// Telea inpainting (cv::inpaint, radius 3) on the same rendered frames and the same holes.
#include <algorithm>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/photo.hpp>

#include "args.hpp"
#include "bench.hpp"
#include "bench_report.hpp"
#include "reprise/core/metrics.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "reprise/warp/fill.hpp"

namespace reprise::cli {

namespace {

using glm::vec3;
using glm::vec4;
constexpr double kHoleTarget = 0.04;

enum HoleKind : uint8_t { kValid = 0, kStrip = 1, kBlob = 2 };

// Where forward warping would leave holes: right of every edge whose left neighbour is nearer by
// more than 10 % (a foreground moving right uncovers a strip of `strip` pixels), then random
// discs of 2..8 px diameter until kHoleTarget of the pixels are holes.
Image<uint8_t> make_holes(const Image<float>& depth, unsigned seed, int strip) {
    const int w = depth.width(), h = depth.height();
    Image<uint8_t> kind(w, h, kValid);
    std::size_t holes = 0;
    auto punch = [&](int x, int y, HoleKind k) {
        if (x >= 0 && y >= 0 && x < w && y < h && kind(x, y) == kValid) kind(x, y) = k, ++holes;
    };
    for (int y = 0; y < h; ++y)
        for (int x = 1; x < w; ++x)
            if (depth(x - 1, y) * 1.1f < depth(x, y))
                for (int k = 0; k < strip; ++k) punch(x + k, y, kStrip);
    std::mt19937 rng(seed);
    const std::size_t target = std::size_t(kHoleTarget * w * h);
    while (holes < target) {
        const int cx = int(rng() % unsigned(w)), cy = int(rng() % unsigned(h));
        const float r = 1.0f + float(rng() % 4);
        for (int dy = -4; dy <= 4; ++dy)
            for (int dx = -4; dx <= 4; ++dx)
                if (dx * dx + dy * dy < r * r) punch(cx + dx, cy + dy, kBlob);
    }
    return kind;
}

struct Method {
    const char* name;
    double ms = 0.0;
    double psnr[3] = {};  // all holes, strips, blobs; summed over frames
};

}  // namespace

Status bench_fill(const BenchOptions& options) {
    BenchScene bench;
    REPRISE_TRY(open_bench_scene(options.scene, bench));
    auto& [scene, path, renderer] = bench;
    std::printf("hole filling on scene %s, %d frames per size, %d threads (ours), renderer %s\n",
                options.scene.c_str(), options.frames, thread_count(), renderer->device().c_str());
    std::printf(
        "holes: strips right of edges whose left neighbour is >10%% nearer (forward "
        "disocclusions, width/240 px wide)\n       + random 2-8 px discs, up to %.0f%% "
        "of the pixels; PSNR on the hole pixels only (display values): all, strips, blobs\n",
        100 * kHoleTarget);
    std::printf("%-11s %6s  %-22s %9s %15s %8s %8s %8s\n", "size", "holes%", "method", "ms",
                "ours/Telea", "PSNR dB", "strips", "blobs");

    std::size_t start = 0;
    const std::string& sizes = options.sizes;
    while (start <= sizes.size()) {
        std::size_t end = sizes.find(',', start);
        if (end == std::string::npos) end = sizes.size();
        int w = 0, h = 0;
        REPRISE_TRY(parse_size(sizes.substr(start, end - start), w, h));
        start = end + 1;

        std::vector<Method> methods = {{"pull-push"},
                                       {"pull-push + depth"},
                                       {"andreev"},
                                       {"andreev + depth"},
                                       {"cv::inpaint Telea r=3"}};
        warp::PullPush pull_push;
        warp::AndreevInpaint andreev;
        Frame frame;
        Image<vec4> holed(w, h), work(w, h);
        Image<vec3> truth(w, h), shown(w, h);
        Image<uint8_t> valid(w, h), masks[3] = {{w, h}, {w, h}, {w, h}};
        cv::Mat bgr(h, w, CV_8UC3), cv_mask(h, w, CV_8UC1), cv_out;
        double hole_fraction = 0.0;

        for (int f = -1; f < options.frames; ++f) {  // frame -1: untimed warm-up of frame 0
            const int index = std::max(f, 0);
            REPRISE_TRY(
                renderer->render_frame(scene, path, index, 30.0, {.width = w, .height = h}, frame));
            const Image<uint8_t> kind =
                make_holes(frame.depth, unsigned(index), std::max(2, w / 240));
            std::size_t holes = 0;
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const uint8_t k = kind(x, y);
                    valid(x, y) = k == kValid;
                    masks[0](x, y) = k != kValid;
                    masks[1](x, y) = k == kStrip;
                    masks[2](x, y) = k == kBlob;
                    holes += k != kValid;
                    holed(x, y) = k == kValid ? frame.color(x, y) : vec4(0.0f);
                }
            to_display(frame.color.view(), truth.view());
            to_display(holed.view(), shown.view());
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const vec3 s = glm::round(shown(x, y) * 255.0f);
                    bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(uchar(s.b), uchar(s.g), uchar(s.r));
                    cv_mask.at<uchar>(y, x) = valid(x, y) ? 0 : 255;
                }

            auto score = [&](Method& m) {
                for (int i = 0; i < 3; ++i)
                    m.psnr[i] += psnr(truth.view(), shown.view(), masks[i].view());
            };
            auto run = [&](Method& m, auto&& fill) {
                work = holed;
                const auto t = BenchClock::now();
                fill();
                const double ms = ms_since(t);
                to_display(work.view(), shown.view());
                if (f < 0) return;
                m.ms += ms;
                score(m);
            };
            run(methods[0], [&] { (void)pull_push.fill(work.view(), valid.view()); });
            run(methods[1],
                [&] { (void)pull_push.fill(work.view(), valid.view(), frame.depth.view()); });
            run(methods[2], [&] { (void)andreev.fill(work.view(), valid.view()); });
            run(methods[3],
                [&] { (void)andreev.fill(work.view(), valid.view(), frame.depth.view()); });
            const auto t = BenchClock::now();
            cv::inpaint(bgr, cv_mask, cv_out, 3.0, cv::INPAINT_TELEA);
            const double telea_ms = ms_since(t);
            if (f < 0) continue;
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const cv::Vec3b p = cv_out.at<cv::Vec3b>(y, x);
                    shown(x, y) = vec3(p[2], p[1], p[0]) / 255.0f;
                }
            methods[4].ms += telea_ms;
            score(methods[4]);
            hole_fraction += double(holes) / (double(w) * h);
            std::fprintf(stderr, "\r[bench] %dx%d %d/%d", w, h, f + 1, options.frames);
        }
        std::fprintf(stderr, "\r%40s\r", "");
        const std::string size = std::to_string(w) + "x" + std::to_string(h);
        const double telea = methods.back().ms;
        for (std::size_t i = 0; i < methods.size(); ++i) {
            const Method& m = methods[i];
            char ratio[32];
            const double r = m.ms / telea;
            if (r < 1.0)
                std::snprintf(ratio, sizeof ratio, "%.3f (1/%.0f)", r, 1.0 / r);
            else
                std::snprintf(ratio, sizeof ratio, "%.2f", r);
            std::printf("%-11s %6.2f  %-22s %9.2f %15s %8.2f %8.2f %8.2f\n",
                        i == 0 ? size.c_str() : "", 100 * hole_fraction / options.frames, m.name,
                        m.ms / options.frames, i + 1 < methods.size() ? ratio : "-",
                        m.psnr[0] / options.frames, m.psnr[1] / options.frames,
                        m.psnr[2] / options.frames);
        }
    }
    return {};
}

}  // namespace reprise::cli
