// reprise bench reuse — shading reuse inside the heavy renderer (Nehab et al. 2007's reprojection
// cache, Mueller et al. 2021's adaptive reshading): per scene and setting, the shading pass with
// and without reuse measured frame by frame in the same run, hit rate, pixels shaded, and the
// error against full shading of the same frame (PSNR, SSIM, FLIP, pixels above T).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "args.hpp"
#include "bench.hpp"
#include "bench_report.hpp"
#include "reprise/core/frame.hpp"

namespace reprise::cli {

namespace {

struct ReuseCase {
    std::string method;   // tiled, random, blocks, interleaved, blocks+smooth, adaptive
    std::string setting;  // e.g. "n=4" or "T=8"
    server::ReuseSettings reuse;
};

struct CaseSummary {
    std::string scene, method, setting;
    double off_shading_ms = 0, reuse_shading_ms = 0;  // sums over frames 1.. (frame 0 has no cache)
    double off_cpu_ms = 0, reuse_cpu_ms = 0;          // the same in CPU time of the process
    double off_render_ms = 0, reuse_render_ms = 0;
    double hits = 0, shaded = 0, covered = 0;  // frames 1..
    double psnr_sum = 0, ssim_sum = 0, flip_sum = 0, above_sum = 0, above_max = 0;
    int frames = 0;

    double speedup() const { return off_cpu_ms / std::max(reuse_cpu_ms, 1e-9); }
    double wall_speedup() const { return off_shading_ms / std::max(reuse_shading_ms, 1e-9); }
    double render_speedup() const { return off_render_ms / std::max(reuse_render_ms, 1e-9); }
    double hit_rate() const { return covered > 0 ? hits / covered : 0.0; }
    double shaded_fraction() const { return covered > 0 ? shaded / covered : 1.0; }
    double above() const { return frames ? above_sum / frames : 0.0; }
};

// Fraction of pixels where any display channel differs by more than `threshold`.
double fraction_above(ImageView<const glm::vec3> a, ImageView<const glm::vec3> b, float threshold) {
    std::size_t above = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            const glm::vec3 d = glm::abs(a(x, y) - b(x, y));
            above += std::max(d.x, std::max(d.y, d.z)) > threshold;
        }
    return a.pixel_count() ? double(above) / double(a.pixel_count()) : 0.0;
}

std::vector<ReuseCase> reuse_cases(bool quick) {
    using server::Refresh;
    using server::Reuse;
    std::vector<ReuseCase> cases;
    auto cache = [&](const char* method, Refresh refresh, int period, float smoothing = 0.0f) {
        cases.push_back(
            {method,
             "n=" + std::to_string(period),
             {.mode = Reuse::Cache, .refresh = refresh, .period = period, .smoothing = smoothing}});
    };
    auto adaptive = [&](int steps, int cap = 16) {
        cases.push_back(
            {"adaptive",
             "T=" + std::to_string(steps) + "/255",
             {.mode = Reuse::Adaptive, .period = cap, .threshold = float(steps) / 255.0f}});
    };
    if (quick) {
        cache("tiled", Refresh::Tiled, 8);
        for (int n : {4, 8, 16}) cache("blocks", Refresh::Blocks, n);
        cache("blocks+smooth", Refresh::Blocks, 8, 0.1f);
        adaptive(8);
        return cases;
    }
    for (int n : {2, 4, 8}) cache("tiled", Refresh::Tiled, n);
    cache("random", Refresh::Random, 4);
    cache("interleaved", Refresh::Interleaved, 4);
    for (int n : {2, 3, 4, 6, 8, 12, 16}) cache("blocks", Refresh::Blocks, n);
    cache("blocks+smooth", Refresh::Blocks, 8, 0.1f);
    cache("blocks+smooth", Refresh::Blocks, 16, 0.1f);
    for (int t : {4, 8, 16}) adaptive(t);
    return cases;
}

// Pixels above T of uniform (blocks) refresh at the shaded fraction `cost` (or, by_time, at the
// speed-up `cost`), linear between the two uniform settings around it; NaN when no pair brackets
// it.
double uniform_at_cost(const std::vector<CaseSummary>& rows, const std::string& scene, double cost,
                       bool by_time = false) {
    std::vector<std::pair<double, double>> curve;
    for (const CaseSummary& r : rows)
        if (r.scene == scene && r.method == "blocks")
            curve.push_back({by_time ? r.speedup() : r.shaded_fraction(), r.above()});
    std::sort(curve.begin(), curve.end());
    for (std::size_t i = 0; i + 1 < curve.size(); ++i) {
        auto [c0, e0] = curve[i];
        auto [c1, e1] = curve[i + 1];
        if (cost >= c0 && cost <= c1)
            return c1 > c0 ? e0 + (e1 - e0) * (cost - c0) / (c1 - c0) : std::min(e0, e1);
    }
    return std::numeric_limits<double>::quiet_NaN();
}

Status run_case(BenchScene& bench, const std::string& scene_name, const ReuseCase& c, int width,
                int height, int frames, CsvFile& csv, CaseSummary& summary) {
    auto& [scene, path, renderer] = bench;
    server::RenderSettings off{.width = width, .height = height, .shading = server::Shading::Heavy};
    server::RenderSettings on = off;
    on.reuse = c.reuse;
    Frame reference, reused;
    Image<glm::vec3> reference_display(width, height), reused_display(width, height);
    summary = {.scene = scene_name, .method = c.method, .setting = c.setting};
    renderer->drop_reuse_cache();
    for (int f = 0; f < frames; ++f) {
        // Full shading and reuse of the same frame back to back: the ratio survives a busy machine.
        auto start = BenchClock::now();
        REPRISE_TRY(renderer->render_frame(scene, path, f, 30.0, off, reference));
        const double off_ms = ms_since(start);
        const double off_shading = renderer->reuse_stats().shading_ms;
        const double off_cpu = renderer->reuse_stats().shading_cpu_ms;
        start = BenchClock::now();
        REPRISE_TRY(renderer->render_frame(scene, path, f, 30.0, on, reused));
        const double on_ms = ms_since(start);
        const server::ReuseStats stats = renderer->reuse_stats();
        to_display(reference.color.view(), reference_display.view());
        to_display(reused.color.view(), reused_display.view());
        ImageError error = image_error(reference_display.view(), reused_display.view());
        const double above =
            fraction_above(reference_display.view(), reused_display.view(), 8.0f / 255.0f);
        csv.error_row(scene_name, c.method, c.setting, f, error, on_ms,
                      {strf("%.4f", off_ms), strf("%.4f", stats.shading_ms),
                       strf("%.4f", off_shading), strf("%.4f", stats.shading_cpu_ms),
                       strf("%.4f", off_cpu), strf("%.6f", stats.hit_rate()),
                       strf("%.6f", stats.shaded_fraction()), strf("%.6f", above)});
        summary.psnr_sum += std::min(error.psnr, 99.0);
        summary.ssim_sum += error.ssim;
        summary.flip_sum += error.flip;
        summary.above_sum += above;
        summary.above_max = std::max(summary.above_max, above);
        ++summary.frames;
        if (f == 0) continue;  // no cache yet: both shade everything
        summary.off_shading_ms += off_shading, summary.reuse_shading_ms += stats.shading_ms;
        summary.off_cpu_ms += off_cpu, summary.reuse_cpu_ms += stats.shading_cpu_ms;
        summary.off_render_ms += off_ms, summary.reuse_render_ms += on_ms;
        summary.hits += double(stats.hits), summary.shaded += double(stats.shaded);
        summary.covered += double(stats.covered);
    }
    csv.flush();
    return {};
}

}  // namespace

Status bench_reuse(const BenchOptions& options) {
    int width = 0, height = 0;
    REPRISE_TRY(parse_size(options.size, width, height));
    if (options.frames < 2) return Status::error("bench reuse: --frames must be at least 2");
    const std::vector<std::string> scenes = options.scenes.empty()
                                                ? std::vector<std::string>{"courtyard", "stroll"}
                                                : split_list(options.scenes);
    const std::string out = options.out.empty() ? "out/bench-reuse" : options.out;
    std::error_code ec;
    std::filesystem::create_directories(out, ec);
    if (ec) return Status::error(out + ": cannot create the folder: " + ec.message());
    CsvFile csv;
    REPRISE_TRY(csv.open(out + "/reuse.csv", std::string(kErrorTimeColumns) +
                                                 ",off_ms,shading_ms,off_shading_ms,shading_cpu_ms,"
                                                 "off_shading_cpu_ms,hit_rate,shaded,above_t"));
    const std::vector<ReuseCase> cases = reuse_cases(options.quick);
    std::vector<CaseSummary> rows;
    std::string device;
    for (const std::string& name : scenes) {
        BenchScene bench;
        REPRISE_TRY(open_bench_scene(name, bench));
        device = bench.renderer->device();
        for (const ReuseCase& c : cases) {
            std::fprintf(stderr, "\r[bench reuse] %s %s %s          ", name.c_str(),
                         c.method.c_str(), c.setting.c_str());
            CaseSummary summary;
            REPRISE_TRY(run_case(bench, name, c, width, height, options.frames, csv, summary));
            rows.push_back(summary);
        }
    }
    std::fprintf(stderr, "\r%60s\r", "");

    std::string table = strf("%-10s %-14s %-10s %8s %8s %8s %8s %7s %7s %8s %8s %9s %9s\n", "scene",
                             "method", "setting", "speedup", "wall", "render", "hit %", "shaded%",
                             "PSNR", "FLIP", "above T%", "max abv%", "off ms");
    for (const CaseSummary& r : rows)
        table += strf(
            "%-10s %-14s %-10s %7.2fx %7.2fx %7.2fx %8.1f %7.1f %7.2f %8.4f %9.3f %9.3f %9.1f\n",
            r.scene.c_str(), r.method.c_str(), r.setting.c_str(), r.speedup(), r.wall_speedup(),
            r.render_speedup(), 100 * r.hit_rate(), 100 * r.shaded_fraction(),
            r.psnr_sum / r.frames, r.flip_sum / r.frames, 100 * r.above(), 100 * r.above_max,
            r.off_cpu_ms / std::max(r.frames - 1, 1));
    table +=
        "\nspeedup: CPU time of the shading pass (depth pre-pass to glFinish; llvmpipe shades on "
        "the "
        "process's threads)\nwithout reuse / with reuse, frames 1.. of the same run; wall: the "
        "same in "
        "wall time (noisy on a shared machine);\nrender: whole render calls in wall time (shadow "
        "map, "
        "read-back); above T: pixels with a display channel off\nby more than 8/255 against full "
        "shading "
        "of the same frame; off ms: CPU ms of the full shading pass.\n\nTargets (issue 11):\n";
    CsvFile summary_csv;
    REPRISE_TRY(summary_csv.open(
        out + "/reuse_summary.csv",
        "scene,method,setting,speedup,wall_speedup,render_speedup,hit_rate,shaded,psnr,flip,"
        "above_t,above_t_max,uniform_above_t_at_equal_cost,uniform_above_t_at_equal_speedup"));
    Report report{.title = "reprise bench reuse: shading reuse in the heavy renderer"};
    report.paragraphs.push_back(
        "Device: " + device + ". " + std::to_string(width) + "x" + std::to_string(height) + ", " +
        std::to_string(options.frames) +
        " frames per scene and setting. Every frame is rendered with full shading and "
        "with reuse back to back; the error is that of the reused frame against the "
        "fully shaded one.");
    for (const std::string& name : scenes) {
        const CaseSummary* best = nullptr;
        std::vector<server::Refresh> kinds;
        std::map<std::string, PlotSeries> curves;
        PlotSeries uniform{.name = "uniform (blocks)"}, adaptive{.name = "adaptive"};
        std::vector<ReportPoint> points;
        for (const CaseSummary& r : rows) {
            if (r.scene != name) continue;
            const double nan = std::numeric_limits<double>::quiet_NaN();
            const double equal =
                r.method == "adaptive" ? uniform_at_cost(rows, name, r.shaded_fraction()) : nan;
            const double equal_time =
                r.method == "adaptive" ? uniform_at_cost(rows, name, r.speedup(), true) : nan;
            summary_csv.row({r.scene, r.method, r.setting, strf("%.4f", r.speedup()),
                             strf("%.4f", r.wall_speedup()), strf("%.4f", r.render_speedup()),
                             strf("%.6f", r.hit_rate()), strf("%.6f", r.shaded_fraction()),
                             strf("%.4f", r.psnr_sum / r.frames),
                             strf("%.6f", r.flip_sum / r.frames), strf("%.6f", r.above()),
                             strf("%.6f", r.above_max), strf("%.6f", equal),
                             strf("%.6f", equal_time)});
            PlotSeries& curve = curves[r.method];
            curve.name = r.method;
            curve.x.push_back(r.speedup());
            curve.y.push_back(100 * r.above());
            points.push_back({.method = r.method,
                              .setting = r.setting,
                              .psnr = r.psnr_sum / r.frames,
                              .ssim = r.ssim_sum / r.frames,
                              .flip = r.flip_sum / r.frames,
                              .ms = r.reuse_cpu_ms / std::max(r.frames - 1, 1)});
            if (r.method == "blocks")
                uniform.x.push_back(100 * r.shaded_fraction()),
                    uniform.y.push_back(100 * r.above());
            if (r.method == "adaptive") {
                adaptive.x.push_back(100 * r.shaded_fraction()),
                    adaptive.y.push_back(100 * r.above());
                table += strf(
                    "  %s adaptive %s: %.3f %% above T at %.1f %% shaded; uniform at equal pixels "
                    "shaded: %s -> %s\n",
                    name.c_str(), r.setting.c_str(), 100 * r.above(), 100 * r.shaded_fraction(),
                    std::isnan(equal) ? "outside the uniform settings' range"
                                      : strf("%.3f %%", 100 * equal).c_str(),
                    std::isnan(equal)   ? "not compared"
                    : r.above() < equal ? "met"
                                        : "not met");
                table +=
                    strf("    at its speed-up %.2fx, uniform: %s (%s)\n", r.speedup(),
                         std::isnan(equal_time) ? "outside the uniform settings' range"
                                                : strf("%.3f %% above T", 100 * equal_time).c_str(),
                         std::isnan(equal_time)   ? "not compared"
                         : r.above() < equal_time ? "adaptive better"
                                                  : "uniform better");
            }
            if (r.above() <= 0.01 && (!best || r.speedup() > best->speedup())) best = &r;
        }
        if (best)
            table +=
                strf("  %s: fastest with <= 1 %% above T: %s %s, %.2fx the shading pass (%s)\n",
                     name.c_str(), best->method.c_str(), best->setting.c_str(), best->speedup(),
                     best->speedup() >= 2.0 ? "met" : "not met");
        else
            table +=
                strf("  %s: no setting keeps <= 1 %% of pixels above T (not met)\n", name.c_str());
        const CaseSummary* full = nullptr;
        for (const CaseSummary& r : rows)
            if (r.scene == name) full = &r;
        points.push_back({.method = "off",
                          .setting = "full shading",
                          .psnr = 99.0,
                          .ssim = 1.0,
                          .flip = 0.0,
                          .ms = full ? full->off_cpu_ms / std::max(full->frames - 1, 1) : 0.0});
        std::vector<PlotSeries> series;
        for (auto& [method, curve] : curves) series.push_back(curve);
        adaptive.dashed = true;
        ReportSection section{
            .title = name,
            .note =
                "Speed-up of the shading pass against the percentage of pixels above T = 8/255 "
                "(one curve per refresh policy, points in the order of their periods); then "
                "adaptive reshading against uniform refresh by pixels shaded; then PSNR against "
                "the shading pass's ms.",
            .html = line_plot_svg(series, {.x_label = "speed-up of the shading pass (x, CPU time)",
                                           .y_label = "% pixels above T",
                                           .log_x = false}) +
                    line_plot_svg({uniform, adaptive}, {.x_label = "% pixels shaded per frame",
                                                        .y_label = "% pixels above T",
                                                        .log_x = false}),
            .points = points,
            .time_label = "shading pass CPU ms per frame (log scale)"};
        report.sections.push_back(std::move(section));
    }
    report.preformatted = table;
    std::printf("%s", table.c_str());
    REPRISE_TRY(write_html_report(out + "/index.html", report));
    std::printf("-> %s/reuse.csv, reuse_summary.csv, index.html\n", out.c_str());
    return {};
}

}  // namespace reprise::cli
