// reprise bench kernels — every (kernel, reference) pair of the kernel harness at every SIMD
// level the CPU runs, against its scalar reference and cv::remap of a float RGBA image of the same
// size, timed in the same run; each level's output is checked against the reference first.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "args.hpp"
#include "bench.hpp"
#include "bench_report.hpp"
#include "kernel_case.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/core/simd.hpp"

namespace reprise::cli {

namespace {

// cv::remap (bilinear) of a w x h float RGBA image along a smooth sub-pixel displacement.
Timing time_remap(int w, int h, int runs) {
    cv::Mat src(h, w, CV_32FC4), dst(h, w, CV_32FC4), map_x(h, w, CV_32FC1), map_y(h, w, CV_32FC1);
    cv::randu(src, 0.0f, 1.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            map_x.at<float>(y, x) = float(x) + 3.3f * std::sin(float(y) * 0.01f);
            map_y.at<float>(y, x) = float(y) + 2.1f * std::cos(float(x) * 0.013f);
        }
    Timing timing;
    for (int i = 0; i < runs + 1; ++i) {
        auto remap = [&] {
            cv::remap(src, dst, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
        };
        if (i == 0)
            remap();  // warm-up
        else
            time_once(timing, remap);
    }
    return timing;
}

template <class Reset, class Run>
Timing time_kernel(int runs, Reset&& reset, Run&& run) {
    Timing timing;
    reset();
    run();  // warm-up
    for (int i = 0; i < runs; ++i) {
        reset();
        time_once(timing, run);
    }
    return timing;
}

Status bench_kernels_size(int w, int h, int runs, CsvFile& csv) {
    const std::vector<simd::Target> targets = simd::available_targets();
    Status status;
    for (const kernels::KernelEntry& entry : kernels::every_kernel()) {
        std::unique_ptr<kernels::KernelCase> k = entry.make();
        k->generate(w, h, kernels::KernelInputs::Random, 7);
        // The peer in between each kernel's runs: the machine's load moves during a run.
        const Timing remap = time_remap(w, h, runs);
        const Timing reference = time_kernel(
            runs, [&] { k->reset_reference(); }, [&] { k->run_reference(); });
        auto line = [&](const char* level, const Timing& t, const char* agrees) {
            std::printf("%-32s %-9s %9.3f %9.3f %9.2fx %9.2fx  %s\n", entry.name, level, t.best(),
                        t.median(), reference.best() / t.best(), t.best() / remap.best(), agrees);
            csv.row({entry.name, level, std::to_string(w), std::to_string(h),
                     strf("%.4f", t.best()), strf("%.4f", t.median()),
                     strf("%.4f", reference.best() / t.best()),
                     strf("%.4f", t.best() / remap.best()), strf("%.4f", remap.best()), agrees,
                     entry.promise});
        };
        line("reference", reference, "-");
        for (const simd::Target& target : targets) {
            simd::force_target(target.bits);
            const Timing t = time_kernel(
                runs, [&] { k->reset(); }, [&] { k->run(); });
            const std::string difference = k->compare();
            simd::force_target(0);
            if (!difference.empty())
                status = Status::error(std::string("bench kernels: ") + entry.name + " at " +
                                       target.name + " differs from its reference: " + difference);
            line(entry.dispatched ? target.name : "built-in", t, difference.empty() ? "yes" : "NO");
            if (!entry.dispatched) break;  // its vector path was chosen when it was compiled
        }
        std::printf("%-32s %-9s %9.3f %9.3f\n", "cv::remap (peer)", "", remap.best(),
                    remap.median());
    }
    return status;
}

}  // namespace

Status bench_kernels(const BenchOptions& options) {
    cv::setNumThreads(thread_count());
    const std::string out = options.out.empty() ? "out/bench-kernels" : options.out;
    std::error_code ec;
    std::filesystem::create_directories(out, ec);
    if (ec) return Status::error("bench kernels: cannot create " + out + ": " + ec.message());
    CsvFile csv;
    REPRISE_TRY(csv.open(out + "/kernels.csv",
                         "kernel,target,width,height,best_ms,median_ms,speedup_vs_reference,"
                         "best_vs_remap,remap_best_ms,agrees,promise"));
    std::printf(
        "warp and codec kernels at every SIMD level this CPU runs (Highway runtime dispatch) "
        "against their "
        "scalar\n"
        "reference and cv::remap (INTER_LINEAR, CV_32FC4, float maps) of an image of the same "
        "size;\n"
        "%d threads (reprise) / %d (OpenCV), best and median of %d runs, ms; random inputs.\n"
        "x ref = reference best / best; x remap = best / remap best; the reverse reprojection's\n"
        "and the forward splat's references are single-threaded (the others run on the same\n"
        "threads as their kernels).\n",
        thread_count(), cv::getNumThreads(), options.frames);
    for (const std::string& size : split_list(options.sizes)) {
        int w = 0, h = 0;
        REPRISE_TRY(parse_size(size, w, h));
        std::printf("\n%dx%d\n%-32s %-9s %9s %9s %10s %10s  %s\n", w, h, "kernel", "level", "best",
                    "median", "x ref", "x remap", "agrees");
        REPRISE_TRY(bench_kernels_size(w, h, options.frames, csv));
    }
    std::printf("\nCSV: %s\n", csv.path().c_str());
    return {};
}

}  // namespace reprise::cli
