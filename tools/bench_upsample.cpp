// reprise bench upsample — spatio-temporal upsampling (Herzog et al. 2010) of low-resolution
// jittered colour against the full-resolution render of the same frames, beside peers in the same
// run: cv::resize (bilinear, bicubic) of the low colour, a jitter-aware cv::warpAffine (bicubic)
// and joint bilateral upsampling without history; then ms per frame at 1080p against cv::remap.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "args.hpp"
#include "bench.hpp"
#include "bench_report.hpp"
#include "reprise/core/metrics.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/warp/upsample.hpp"

namespace reprise::cli {

namespace {

struct LowresSequence {
    std::vector<Frame> full;
    std::vector<Image<glm::vec4>> low;
    std::vector<glm::vec2> jitter;
};

Status render_sequence(BenchScene& bench, int width, int height, int factor, int frames,
                       LowresSequence& seq) {
    seq.full.resize(std::size_t(frames));
    seq.low.resize(std::size_t(frames));
    seq.jitter.resize(std::size_t(frames));
    for (int i = 0; i < frames; ++i) {
        REPRISE_TRY(bench.renderer->render_frame_lowres(bench.scene, bench.path, i, 30.0,
                                                        {.width = width, .height = height}, factor,
                                                        seq.full[std::size_t(i)], seq.low[std::size_t(i)],
                                                        seq.jitter[std::size_t(i)]));
        std::fprintf(stderr, "\r[bench] rendering %d/%d", i + 1, frames);
    }
    std::fprintf(stderr, "\r%40s\r", "");
    return {};
}

cv::Mat as_mat(const Image<glm::vec4>& image) {
    return cv::Mat(image.height(), image.width(), CV_32FC4, const_cast<glm::vec4*>(image.data()));
}
cv::Mat as_mat(Image<glm::vec4>& image) {
    return cv::Mat(image.height(), image.width(), CV_32FC4, image.data());
}

// One upsampling method over a sequence, frame by frame in order (the temporal ones keep state).
struct Method {
    std::string method, setting;
    // Upsamples frame i of the sequence into out; `first` is true on the first frame of a run.
    std::function<void(const LowresSequence&, int, bool, Image<glm::vec4>&)> run;
};

std::vector<Method> methods() {
    auto herzog = [](warp::UpsampleOptions options) {
        auto upsampler = std::make_shared<warp::SpatioTemporalUpsampler>(options);
        return [upsampler](const LowresSequence& s, int i, bool first, Image<glm::vec4>& out) {
            if (first) upsampler->reset();
            upsampler->upsample(s.low[std::size_t(i)].view(), s.jitter[std::size_t(i)],
                                s.full[std::size_t(i)].view(), out.view());
        };
    };
    auto resize = [](int interpolation) {
        return [interpolation](const LowresSequence& s, int i, bool, Image<glm::vec4>& out) {
            cv::Mat dst = as_mat(out);
            cv::resize(as_mat(s.low[std::size_t(i)]), dst, dst.size(), 0, 0, interpolation);
        };
    };
    // The low image placed where its samples are (scale + jitter), then bicubic.
    auto jitter_aware = [](const LowresSequence& s, int i, bool, Image<glm::vec4>& out) {
        const Image<glm::vec4>& low = s.low[std::size_t(i)];
        const glm::vec2 j = s.jitter[std::size_t(i)];
        const double sx = double(out.width()) / low.width(), sy = double(out.height()) / low.height();
        const cv::Matx23d to_low(1.0 / sx, 0.0, (0.5 - j.x) / sx - 0.5, 0.0, 1.0 / sy, (0.5 - j.y) / sy - 0.5);
        cv::Mat dst = as_mat(out);
        cv::warpAffine(as_mat(low), dst, to_low, dst.size(), cv::INTER_CUBIC | cv::WARP_INVERSE_MAP,
                       cv::BORDER_REPLICATE);
    };
    return {
        {"herzog", "steered", herzog({})},
        {"herzog", "paper (no clamp)", herzog({.history_clamp = -1.0f})},
        {"herzog", "fixed 0.9", herzog({.gradient_steering = false})},
        {"jbu", "no history", herzog({.history_weight = 0.0f})},
        {"cv::resize", "bilinear", resize(cv::INTER_LINEAR)},
        {"cv::resize", "bicubic", resize(cv::INTER_CUBIC)},
        {"cv::warpAffine", "bicubic, jitter-aware", jitter_aware},
    };
}

// Indices into methods() of the peers the report singles out.
constexpr std::size_t kJbu = 3, kBilinear = 4, kJitterAware = 6;

struct Summary {
    double psnr = 0, ssim = 0, flip = 0, ms = 0;
    int frames = 0;
};

Status speed_run(const BenchOptions& options, CsvFile& csv, std::string& text) {
    int w = 0, h = 0;
    REPRISE_TRY(parse_size(options.speed_size, w, h));
    BenchScene bench;
    REPRISE_TRY(open_bench_scene(options.speed_scene, bench));
    const int frames = std::max(2, options.speed_frames);
    LowresSequence seq;
    REPRISE_TRY(render_sequence(bench, w, h, 4, frames, seq));
    std::vector<Method> all = methods();
    std::vector<Timing> times(all.size());
    Timing remap_times;
    Image<glm::vec4> out(w, h), remapped(w, h);
    cv::Mat map_x(h, w, CV_32FC1), map_y(h, w, CV_32FC1);
    for (int i = 0; i < frames; ++i) {
        const Frame& f = seq.full[std::size_t(i)];
        for (std::size_t m = 0; m < all.size(); ++m) {
            auto run = [&] { all[m].run(seq, i, i == 0, out); };
            if (i > 0) time_once(times[m], run);  // the first frame has no history: untimed
            else run();
        }
        // The peer: cv::remap of this frame's full-resolution colour along its motion.
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const glm::vec2 m = f.motion(x, y);
                const bool ok = std::isfinite(m.x) && std::isfinite(m.y);
                map_x.at<float>(y, x) = ok ? float(x) + m.x : -1e6f;
                map_y.at<float>(y, x) = ok ? float(y) + m.y : -1e6f;
            }
        cv::Mat dst = as_mat(remapped);
        auto remap = [&] {
            cv::remap(as_mat(f.color), dst, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
        };
        if (i > 0) time_once(remap_times, remap);
        else remap();
        std::fprintf(stderr, "\r[bench] speed %dx%d %d/%d", w, h, i + 1, frames);
    }
    std::fprintf(stderr, "\r%40s\r", "");
    text += strf("\nms per %dx%d frame (%s, 1/4 of the pixels, %d timed frames, %d threads) against "
                 "cv::remap (INTER_LINEAR, CV_32FC4, float maps) of the same frame:\n",
                 w, h, options.speed_scene.c_str(), frames - 1, thread_count());
    text += strf("%-16s %-22s %9s %9s %10s %10s\n", "method", "setting", "best ms", "median ms",
                 "best/remap", "med/remap");
    auto line = [&](const std::string& method, const std::string& setting, const Timing& t) {
        text += strf("%-16s %-22s %9.2f %9.2f %9.2fx %9.2fx\n", method.c_str(), setting.c_str(),
                     t.best(), t.median(), t.best() / remap_times.best(), t.median() / remap_times.median());
        csv.row({strf("%dx%d", w, h), method, setting, strf("%.4f", t.best()), strf("%.4f", t.median()),
                 strf("%.4f", t.best() / remap_times.best()), strf("%.4f", t.median() / remap_times.median())});
    };
    for (std::size_t m = 0; m < all.size(); ++m) line(all[m].method, all[m].setting, times[m]);
    line("cv::remap", "peer", remap_times);
    return {};
}

}  // namespace

Status bench_upsample(const BenchOptions& options) {
    int width = 0, height = 0;
    REPRISE_TRY(parse_size(options.size, width, height));
    std::vector<std::string> scenes = split_list(options.scenes);
    if (scenes.empty())
        for (const server::SceneInfo& s : server::builtin_scenes()) scenes.push_back(s.name);
    std::vector<int> factors;
    if (options.factor == 0) factors = {4, 2};
    else if (options.factor == 2 || options.factor == 4) factors = {options.factor};
    else return Status::error("bench upsample: --factor must be 2 or 4 (pixels per low-resolution sample)");
    const std::string out_dir = options.out.empty() ? "out/bench-upsample" : options.out;
    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    if (ec) return Status::error(out_dir + ": cannot create the folder: " + ec.message());
    cv::setNumThreads(thread_count());

    CsvFile csv, speed_csv;
    REPRISE_TRY(csv.open(out_dir + "/upsample.csv", std::string(kErrorTimeColumns) + ",factor"));
    REPRISE_TRY(speed_csv.open(out_dir + "/speed.csv", "size,method,setting,best_ms,median_ms,best_over_remap,median_over_remap"));
    const std::vector<Method> all = methods();
    // (factor, scene, method index) -> summary
    std::map<std::tuple<int, std::string, std::size_t>, Summary> summaries;
    Report report;
    report.title = "reprise bench upsample";
    report.paragraphs.push_back(strf(
        "Colour rendered at 1/2 (W/2 x H) or 1/4 (W/2 x H/2) of the pixels with a per-frame jitter "
        "cycling over the full pixels of each low pixel, upsampled to %dx%d with the full-resolution "
        "G-buffer and compared with the full-resolution render of the same frames (display values). "
        "%d frames per scene from t = 0, each frame's fastest of %d runs. herzog: Herzog et al. 2010 "
        "(steered: temporal gradients steer the history, which is clamped to the colour box of the "
        "current samples on the same surface; paper: without that clamp; fixed 0.9: a constant "
        "fall-off, with the clamp); jbu: the "
        "same tri-weight joint bilateral filter without history; cv::resize ignores the jitter; "
        "cv::warpAffine places the low samples where they were taken.",
        width, height, options.frames, options.repeat));
    std::vector<ReportImage> images;

    Image<glm::vec4> out(width, height);
    Image<glm::vec3> truth_display(width, height), test_display(width, height);
    for (int factor : factors) {
        for (const std::string& scene_name : scenes) {
            BenchScene bench;
            REPRISE_TRY(open_bench_scene(scene_name, bench));
            LowresSequence seq;
            REPRISE_TRY(render_sequence(bench, width, height, factor, options.frames, seq));
            std::vector<Image<Rgb8>> last_pictures;
            std::vector<std::string> labels;
            for (std::size_t m = 0; m < all.size(); ++m) {
                std::map<int, double> fastest;
                for (int run = 0; run < std::max(1, options.repeat); ++run) {
                    for (int i = 0; i < options.frames; ++i) {
                        const auto start = BenchClock::now();
                        all[m].run(seq, i, i == 0, out);
                        keep_fastest(fastest, i, ms_since(start));
                    }
                }
                // The last run's frames are measured (every run gives the same pictures).
                for (int run_frame = 0; run_frame < options.frames; ++run_frame) {
                    all[m].run(seq, run_frame, run_frame == 0, out);
                    to_display(seq.full[std::size_t(run_frame)].color.view(), truth_display.view());
                    to_display(out.view(), test_display.view());
                    const ImageError e = image_error(truth_display.view(), test_display.view());
                    csv.error_row(scene_name, all[m].method, all[m].setting, run_frame, e,
                                  fastest[run_frame], {std::to_string(factor)});
                    Summary& s = summaries[{factor, scene_name, m}];
                    s.psnr += e.psnr;
                    s.ssim += e.ssim;
                    s.flip += e.flip;
                    s.ms += fastest[run_frame];
                    ++s.frames;
                    if (run_frame == options.frames - 1 && (m == 0 || m == kJbu || m == kBilinear || m == kJitterAware)) {
                        Image<Rgb8> picture;
                        to_rgb8(test_display.view(), picture);
                        last_pictures.push_back(std::move(picture));
                        labels.push_back(all[m].method + " " + all[m].setting);
                    }
                }
                std::fprintf(stderr, "\r[bench] 1/%d %s %s %s    ", factor, scene_name.c_str(),
                             all[m].method.c_str(), all[m].setting.c_str());
            }
            std::fprintf(stderr, "\r%60s\r", "");
            Image<Rgb8> truth;
            to_display(seq.full.back().color.view(), truth_display.view());
            to_rgb8(truth_display.view(), truth);
            const std::string picture = strf("%s_1of%d.png", scene_name.c_str(), factor);
            REPRISE_TRY(write_worst_window_sheet(out_dir + "/" + picture, std::move(last_pictures),
                                                 labels, truth, 640));
            images.push_back({picture, strf("%s, 1/%d of the pixels, last frame: %s (worst window of herzog)",
                                            scene_name.c_str(), factor, "herzog, jbu, bilinear, warpAffine")});
            csv.flush();
        }
    }

    std::string table = strf("%-9s %-6s %-16s %-22s %8s %7s %7s %9s %10s\n", "scene", "pixels",
                             "method", "setting", "PSNR", "SSIM", "FLIP", "ms", "vs bilin.");
    for (int factor : factors) {
        ReportSection section;
        section.title = strf("1/%d of the pixels (mean over scenes)", factor);
        section.note = "Mean PSNR over every scene and frame against the mean ms per frame at the bench size.";
        section.time_label = "ms per upsampled frame (log scale)";
        std::vector<Summary> means(all.size());
        for (const std::string& scene_name : scenes) {
            const Summary& bilinear = summaries[{factor, scene_name, kBilinear}];
            for (std::size_t m = 0; m < all.size(); ++m) {
                const Summary& s = summaries[{factor, scene_name, m}];
                const double n = std::max(1, s.frames);
                table += strf("%-9s 1/%-4d %-16s %-22s %8.2f %7.4f %7.4f %9.2f %+9.2f\n", scene_name.c_str(),
                              factor, all[m].method.c_str(), all[m].setting.c_str(), s.psnr / n, s.ssim / n,
                              s.flip / n, s.ms / n, (s.psnr - bilinear.psnr) / n);
                means[m].psnr += s.psnr / n / double(scenes.size());
                means[m].ssim += s.ssim / n / double(scenes.size());
                means[m].flip += s.flip / n / double(scenes.size());
                means[m].ms += s.ms / n / double(scenes.size());
            }
        }
        for (std::size_t m = 0; m < all.size(); ++m) {
            section.points.push_back({all[m].method, all[m].setting, means[m].psnr, means[m].ssim,
                                      means[m].flip, means[m].ms});
            table += strf("%-9s 1/%-4d %-16s %-22s %8.2f %7.4f %7.4f %9.2f %+9.2f\n", "MEAN", factor,
                          all[m].method.c_str(), all[m].setting.c_str(), means[m].psnr, means[m].ssim,
                          means[m].flip, means[m].ms, means[m].psnr - means[kBilinear].psnr);
        }
        for (const ReportImage& image : images)
            if (image.file.find(strf("_1of%d", factor)) != std::string::npos) section.images.push_back(image);
        report.sections.push_back(std::move(section));
    }
    std::string speed_text;
    if (options.speed_frames > 0) REPRISE_TRY(speed_run(options, speed_csv, speed_text));
    std::printf("%s%s", table.c_str(), speed_text.c_str());
    report.preformatted = table + speed_text;
    REPRISE_TRY(write_html_report(out_dir + "/index.html", report));
    std::printf("\n%s/upsample.csv, speed.csv, index.html\n", out_dir.c_str());
    return {};
}

}  // namespace reprise::cli
