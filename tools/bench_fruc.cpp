// reprise bench fruc — frame-rate upconversion error against run time: every mode, warp and fill
// beside ffmpeg's minterpolate, OpenCV DIS flow and Telea inpainting, on the same rendered frames.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <glm/common.hpp>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "args.hpp"
#include "bench.hpp"
#include "bench_report.hpp"
#include "fruc_options.hpp"
#include "peers.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/core/metrics.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "reprise/warp/fruc.hpp"

namespace reprise::cli {

namespace {

namespace fs = std::filesystem;

const char* const kFfmpeg = "ffmpeg-minterpolate";
const char* const kDis = "opencv-dis";
const char* const kVectors = "rendered-vectors";

// Scenes no default was tuned on (glTF sample models from Debian's assimp-testmodels under their
// default orbit): `--scenes held-out`, and part of the default list.
const char* const kHeldOutDir = "/usr/share/assimp/models/glTF2/";
const char* const kHeldOut[] = {"2CylinderEngine-glTF-Binary/2CylinderEngine.glb",
                                "glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf",
                                "BoxTextured-glTF-Binary/BoxTextured.glb"};

bool is_held_out(const std::string& scene) {
    return scene.rfind(kHeldOutDir, 0) == 0 || is_sequence(scene);
}

// Each --in folder holds a sequence (input/, truth/) or folders that do.
bool holds_sequence(const fs::path& dir) { return holds_exr(dir / "input"); }

// The --scenes list with `held-out` expanded, then the --in sequences; with neither, every
// built-in scene and the held-out ones.
std::vector<std::string> scene_list(const std::string& spec, const std::string& in) {
    std::vector<std::string> given = split_list(spec), scenes;
    if (given.empty() && in.empty()) {
        for (const server::SceneInfo& s : server::builtin_scenes()) scenes.push_back(s.name);
        given = {"held-out"};
    }
    for (const std::string& name : given) {
        if (name != "held-out") {
            scenes.push_back(name);
            continue;
        }
        for (const char* model : kHeldOut)
            if (fs::exists(std::string(kHeldOutDir) + model))
                scenes.push_back(std::string(kHeldOutDir) + model);
    }
    for (const std::string& sequence : sequence_folders(in, holds_sequence))
        scenes.push_back(sequence);
    return scenes;
}

struct Setting {
    std::string method, setting;
    warp::FrucOptions options;
    bool with_telea = false;   // also score Telea inpainting of this run's holes (fill none)
    bool refine_pair = false;  // the default's refinement on/off pair: region scores for both
};

const char* const kRefineOff = "grid+pullpush-refine";  // the default without refinement

std::vector<Setting> fruc_settings(bool quick) {
    std::vector<Setting> settings;
    auto add = [&](const std::string& mode, const std::string& warp_name, const std::string& fill) {
        Setting s{mode, warp_name == "auto" ? std::string("auto") : warp_name + "+" + fill};
        Status parsed = parse_fruc_options(mode, warp_name, fill, s.options);
        REPRISE_ASSERT(parsed.ok());
        s.with_telea = !quick && mode == "interpolate" && warp_name == "grid" && fill == "none";
        settings.push_back(s);
    };
    // The default with and without motion refinement, both scored on the region it refines.
    auto add_refine_pair = [&] {
        add("interpolate", "grid", "pullpush");
        settings.back().refine_pair = true;
        Setting off = settings.back();
        off.setting = kRefineOff;
        off.options.refine.enabled = false;
        settings.push_back(off);
    };
    // The default in linear light (FrucOptions::perceptual off), beside it.
    auto add_linear = [&](const std::string& mode) {
        add(mode, "grid", "pullpush");
        settings.back().setting += "-linear";
        settings.back().options.perceptual = false;
    };
    if (quick) {
        add_refine_pair();
        add_linear("interpolate");
        // The grid's other colour fetch, beside the default one.
        add("interpolate", warp::FrucOptions{}.grid.bicubic ? "grid-bilinear" : "grid-bicubic",
            "pullpush");
        add("interpolate", "reverse", "pullpush");
        add("interpolate", "grid", "patch");
        add("interpolate", "splat", "none");
        add("extrapolate", "grid", "pullpush");
        add_linear("extrapolate");
        add("interpolate", "auto", "auto");
        add("extrapolate", "auto", "auto");
        return settings;
    }
    for (const char* mode : {"interpolate", "extrapolate"}) {
        for (const char* warp_name : {"reverse", "splat", "grid"})
            for (const char* fill : {"pullpush", "andreev", "none"}) {
                if (std::string(mode) == "interpolate" && std::string(warp_name) == "grid" &&
                    std::string(fill) == "pullpush")
                    add_refine_pair();
                else
                    add(mode, warp_name, fill);
            }
        add_linear(mode);
        add(mode, "grid", "patch");
        add(mode, "auto", "auto");
    }
    return settings;
}

struct Score {
    int frame = 0;
    ImageError error;
    double ms = 0.0;
};

// One method and setting on one scene.
struct Run {
    std::string method, setting;
    std::vector<Score> scores;
    int worst_frame = -1;
    double worst_psnr = INFINITY;
    Image<Rgb8> worst;                  // the lowest-PSNR frame as shown
    std::map<int, Image<Rgb8>> frames;  // peers: every scored frame, for the comparison picture
    // The refinement pair: squared display error summed over the refined region, its pixels.
    double region_squared = 0.0;
    std::size_t region_pixels = 0;
    double refine_ms = 0.0;  // the converter's refinement time per made frame
    double region_psnr() const {
        return region_pixels ? -10.0 * std::log10(region_squared / double(region_pixels)) : NAN;
    }

    ReportPoint mean() const {
        ReportPoint p{method, setting};
        for (const Score& s : scores) {
            p.psnr += s.error.psnr, p.ssim += s.error.ssim, p.flip += s.error.flip, p.ms += s.ms;
        }
        const double n = scores.empty() ? NAN : double(scores.size());
        p.psnr /= n, p.ssim /= n, p.flip /= n, p.ms /= n;
        return p;
    }
    bool ours() const { return method == "interpolate" || method == "extrapolate"; }
};

struct SceneFrames {
    std::string name;                      // folder-safe
    std::vector<Frame> input;              // 30 Hz
    std::vector<Image<Rgb8>> input_shown;  // their display values in 8 bits: the peers' input
    std::vector<Image<glm::vec3>> truth;   // display values at 30 K Hz; empty at input instants
    // Per scored frame, where refinement found the warped sides disagreeing (the refinement
    // pair's first run fills it; the second is scored on the same pixels).
    std::map<int, Image<uint8_t>> regions;
    int factor = 2;
    int last() const { return (int(input.size()) - 1) * factor; }
    bool scored(int j) const { return j % factor != 0 && j > 0 && j < last(); }
};

void record(Run& run, int frame, const Image<glm::vec3>& display, const Image<glm::vec3>& truth,
            double ms, bool keep_frame) {
    Score score{frame, image_error(truth.view(), display.view()), ms};
    run.scores.push_back(score);
    if (keep_frame) to_rgb8(display.view(), run.frames[frame]);
    if (run.worst_frame < 0 || score.error.psnr < run.worst_psnr) {
        run.worst_frame = frame;
        run.worst_psnr = score.error.psnr;
        to_rgb8(display.view(), run.worst);
    }
}

Status render_scene(server::Renderer& renderer, const std::string& scene_name, int frames,
                    int factor, int w, int h, int aa, const std::string& exr_dir,
                    SceneFrames& out) {
    server::Scene scene;
    server::CameraPath path;
    REPRISE_TRY(server::load_scene(scene_name, scene, path));
    // A model's own camera may stand still: the held-out models are seen from an orbit.
    if (is_held_out(scene_name))
        REPRISE_TRY(server::parse_camera_spec("orbit:speed=0.5", scene, path, path));
    // Scenes built for heavy shading (their shadows come from its shadow map) get it.
    const server::RenderSettings settings{
        .width = w,
        .height = h,
        .shading = scene.heavy_shading ? server::Shading::Heavy : server::Shading::Lit,
        .aa_samples = aa};
    out.factor = factor;
    if (!exr_dir.empty()) {
        std::error_code ec;
        for (const char* sub : {"/input", "/truth"}) {
            fs::create_directories(exr_dir + sub, ec);
            if (ec)
                return Status::error(exr_dir + sub + ": cannot create the folder: " + ec.message());
        }
    }
    out.input.resize(frames);
    out.input_shown.resize(frames);
    for (int i = 0; i < frames; ++i) {
        REPRISE_TRY(renderer.render_frame(scene, path, i, 30.0, settings, out.input[i]));
        out.input_shown[i].resize(w, h);
        // A UI layer is scored as shown: drawn over the scene (peers get it in their input).
        Image<glm::vec4> shown(w, h);
        composite_ui(out.input[i].color.view(), out.input[i].ui.view(), shown.view());
        visualize_color(shown.view(), out.input_shown[i].view());
        if (!exr_dir.empty())
            REPRISE_TRY(write_frame(frame_path(exr_dir + "/input", i), out.input[i]));
        std::fprintf(stderr, "\r[fruc] %s: rendering input %d/%d   ", out.name.c_str(), i + 1,
                     frames);
    }
    out.truth.assign(out.last() + 1, {});
    Frame truth;
    for (int j = 0; j <= out.last(); ++j) {
        if (!out.scored(j) && exr_dir.empty()) continue;  // the inputs' instants need no truth
        REPRISE_TRY(renderer.render_frame(scene, path, j, 30.0 * factor, settings, truth));
        if (!exr_dir.empty()) REPRISE_TRY(write_frame(frame_path(exr_dir + "/truth", j), truth));
        if (!out.scored(j)) continue;
        out.truth[j].resize(w, h);
        composite_ui(truth.color.view(), truth.ui.view(), truth.color.view());
        reprise::to_display(truth.color.view(), out.truth[j].view());
        std::fprintf(stderr, "\r[fruc] %s: rendering truth %d/%d   ", out.name.c_str(), j,
                     out.last());
    }
    std::fprintf(stderr, "\n");
    return {};
}

// A sequence folder as `--exr` writes it (and scripts/blender-scenes): DIR/input at 30 Hz,
// DIR/truth at 30 K Hz over the same time; up to `frames` inputs.
Status read_scene(const std::string& dir, int frames, int factor, SceneFrames& out) {
    Sequence inputs, truths;
    REPRISE_TRY(open_sequence(dir + "/input", inputs));
    REPRISE_TRY(open_sequence(dir + "/truth", truths));
    const int n =
        std::min({frames, int(inputs.files.size()), (int(truths.files.size()) - 1) / factor + 1});
    if (n < 2)
        return Status::error(dir + ": " + std::to_string(inputs.files.size()) + " input and " +
                             std::to_string(truths.files.size()) + " truth frames; x" +
                             std::to_string(factor) + " needs 2 and " + std::to_string(factor + 1));
    out.factor = factor;
    out.input.resize(n);
    out.input_shown.resize(n);
    auto same_size = [&](const Frame& f, const std::string& path) {
        return f.width() == out.input[0].width() && f.height() == out.input[0].height()
                   ? Status()
                   : Status::error(path + ": size differs from " + inputs.files[0]);
    };
    for (int i = 0; i < n; ++i) {
        std::fprintf(stderr, "\r[fruc] %s: reading input %d/%d   ", out.name.c_str(), i + 1, n);
        REPRISE_TRY(read_frame(inputs, i, out.input[i]));
        REPRISE_TRY(same_size(out.input[i], inputs.files[i]));
        out.input_shown[i].resize(out.input[i].width(), out.input[i].height());
        visualize_color(out.input[i].color.view(), out.input_shown[i].view());
    }
    out.truth.assign(out.last() + 1, {});
    Frame truth;
    for (int j = 0; j <= out.last(); ++j) {
        if (!out.scored(j)) continue;
        std::fprintf(stderr, "\r[fruc] %s: reading truth %d/%d   ", out.name.c_str(), j,
                     out.last());
        REPRISE_TRY(read_frame(truths, j, truth));
        REPRISE_TRY(same_size(truth, truths.files[j]));
        out.truth[j].resize(truth.width(), truth.height());
        reprise::to_display(truth.color.view(), out.truth[j].view());
    }
    std::fprintf(stderr, "\n");
    return {};
}

// Times send() alone; each frame it made gets an equal share of that time, the fastest of
// `repeat` runs over the sequence. Frames are scored on the first run.
Status run_ours(SceneFrames& scene, const Setting& setting, int repeat, Run& run, Run* telea,
                warp::FrucCounters& counters) {
    const int w = scene.input[0].width(), h = scene.input[0].height();
    Frame out;
    Image<glm::vec3> display(w, h);
    Image<uint8_t> holes(w, h);
    std::map<int, double> send_ms, telea_ms;
    Image<uint8_t> region;
    const bool capture = setting.refine_pair && setting.options.refine.enabled;
    if (capture) scene.regions.clear();
    for (int rep = 0; rep < repeat; ++rep) {
        warp::FrucOptions options = setting.options;
        options.composite_ui = true;  // scored as shown
        warp::FrameRateConverter converter;
        REPRISE_TRY(warp::FrameRateConverter::create(scene.factor, options, converter));
        int index = 0;
        for (const Frame& input : scene.input) {
            auto start = BenchClock::now();
            REPRISE_TRY(converter.send(input));
            const double ms = ms_since(start);
            if (capture && rep == 0) converter.refine_region(region);
            std::vector<int> made;
            while (converter.receive(out)) {
                const int j = index++;
                if (j % scene.factor == 0) continue;  // an input passed through
                made.push_back(j);
                if (!scene.scored(j)) continue;  // beyond the last input: no truth to compare
                if (rep == 0 || telea) to_display(out.color.view(), display.view());
                if (rep == 0) record(run, j, display, scene.truth[j], 0.0, false);
                if (capture && rep == 0) scene.regions[j] = region;
                if (setting.refine_pair && rep == 0 && scene.regions.count(j)) {
                    const Image<uint8_t>& mask = scene.regions.at(j);
                    std::size_t pixels = 0;
                    for (int y = 0; y < h; ++y)
                        for (int x = 0; x < w; ++x) pixels += mask(x, y) != 0;
                    if (pixels > 0) {
                        const double db = psnr(scene.truth[j].view(), display.view(), mask.view());
                        run.region_squared += std::pow(10.0, -db / 10.0) * double(pixels);
                        run.region_pixels += pixels;
                    }
                }
                if (!telea) continue;
                // With fill none the converter leaves holes at colour 0 and depth +inf.
                for (int y = 0; y < h; ++y)
                    for (int x = 0; x < w; ++x)
                        holes(x, y) =
                            out.color(x, y) == glm::vec4(0.0f) && std::isinf(out.depth(x, y));
                auto telea_start = BenchClock::now();
                inpaint_telea(display.view(), holes.view());
                keep_fastest(telea_ms, j, ms_since(telea_start));
                if (rep == 0) record(*telea, j, display, scene.truth[j], 0.0, false);
            }
            for (int j : made) keep_fastest(send_ms, j, ms / double(made.size()));
        }
        const warp::FrucCounters& c = converter.counters();
        if (rep == 0 && c.outputs > 0) run.refine_ms = c.refine_ms / double(c.outputs);
        if (rep == 0) counters = c;
    }
    for (Score& s : run.scores) s.ms = send_ms[s.frame];
    if (telea)
        for (Score& s : telea->scores) s.ms = send_ms[s.frame] + telea_ms[s.frame];
    return {};
}

void run_dis(const SceneFrames& scene, int repeat, Run& run) {
    const int w = scene.input[0].width(), h = scene.input[0].height(), k_max = scene.factor;
    DisInterpolator dis;
    Image<Rgb8> shown(w, h);
    Image<glm::vec3> display;
    std::map<int, double> fastest;
    for (int rep = 0; rep < repeat; ++rep)
        for (std::size_t i = 0; i + 1 < scene.input.size(); ++i) {
            auto start = BenchClock::now();
            dis.set_pair(scene.input_shown[i].view(), scene.input_shown[i + 1].view());
            const double pair_ms = ms_since(start);
            for (int k = 1; k < k_max; ++k) {
                start = BenchClock::now();
                dis.interpolate(float(k) / float(k_max), shown.view());
                const int j = int(i) * k_max + k;
                keep_fastest(fastest, j, ms_since(start) + pair_ms / (k_max - 1));
                if (rep > 0) continue;
                from_rgb8(shown.view(), display);
                record(run, j, display, scene.truth[j], 0.0, true);
            }
        }
    for (Score& s : run.scores) s.ms = fastest[s.frame];
}

void run_vectors(const SceneFrames& scene, int repeat, Run& run) {
    RenderedVectorsInterpolator peer;
    Image<glm::vec3> display;
    std::map<int, double> fastest;
    for (int rep = 0; rep < repeat; ++rep)
        for (std::size_t i = 0; i + 1 < scene.input.size(); ++i)
            for (int k = 1; k < scene.factor; ++k) {
                const auto start = BenchClock::now();
                peer.interpolate(scene.input[i], scene.input[i + 1], float(k) / float(scene.factor),
                                 display);
                const int j = int(i) * scene.factor + k;
                keep_fastest(fastest, j, ms_since(start));
                if (rep == 0) record(run, j, display, scene.truth[j], 0.0, true);
            }
    for (Score& s : run.scores) s.ms = fastest[s.frame];
}

Status run_ffmpeg(const SceneFrames& scene, const std::string& scratch_dir, int repeat, Run& run) {
    std::vector<Image<Rgb8>> output, again;
    double seconds = 0.0, fastest = INFINITY;
    for (int rep = 0; rep < repeat; ++rep) {
        REPRISE_TRY(ffmpeg_minterpolate(scene.input_shown, scene.factor, scratch_dir,
                                        rep ? again : output, seconds));
        fastest = std::min(fastest, seconds);
    }
    const int synthesized = (int(scene.input.size()) - 1) * (scene.factor - 1);
    Image<glm::vec3> display;
    for (int j = 1; j < scene.last(); ++j) {
        if (!scene.scored(j)) continue;
        from_rgb8(output[j].view(), display);
        record(run, j, display, scene.truth[j], 1e3 * fastest / synthesized, true);
    }
    return {};
}

// Full frames and the crop where ours errs most: ours, truth, the better peer.
Status comparison_picture(const SceneFrames& scene, const Run& ours, const Run* peer,
                          const std::string& path) {
    const int j = ours.worst_frame;
    Image<Rgb8> truth;
    to_rgb8(scene.truth[j].view(), truth);
    std::vector<Image<Rgb8>> images = {ours.worst, truth};
    std::vector<std::string> labels = {"ours " + ours.setting + " " + db(ours.worst_psnr),
                                       "truth, frame " + std::to_string(j)};
    if (peer && peer->frames.count(j)) {
        images.push_back(peer->frames.at(j));
        std::string label = peer->method;
        for (const Score& s : peer->scores)
            if (s.frame == j) label += " " + db(s.error.psnr);
        labels.push_back(label);
    }
    return write_worst_window_sheet(path, std::move(images), std::move(labels), truth);
}

const Run* best_of(const std::vector<Run>& runs, const std::function<bool(const Run&)>& wanted) {
    const Run* best = nullptr;
    for (const Run& r : runs)
        if (wanted(r) && !r.scores.empty() && (!best || r.mean().psnr > best->mean().psnr))
            best = &r;
    return best;
}

void progress(const std::string& scene, const Run& run) {
    ReportPoint p = run.mean();
    std::fprintf(stderr, "[fruc] %s: %-19s %-17s %6.2f dB %8.2f ms\n", scene.c_str(),
                 run.method.c_str(), run.setting.c_str(), p.psnr, p.ms);
}

// The auto choice's predictors for every scored frame, both modes: the fit of its models
// (scripts/fit_auto.py) joins them with fruc.csv.
void write_predictors(std::FILE* file, const SceneFrames& scene) {
    for (std::size_t i = 0; i + 1 < scene.input.size(); ++i) {
        const warp::FramePredictors later = warp::survey_predictors(scene.input[i + 1]),
                                    earlier = warp::survey_predictors(scene.input[i]);
        for (int k = 1; k < scene.factor; ++k) {
            const int j = int(i) * scene.factor + k;
            if (!scene.scored(j)) continue;
            const float s = float(k) / float(scene.factor);
            std::fprintf(file, "%s,%d,interpolate,%.4f,%.4f,%.4f,%.6f\n", scene.name.c_str(), j,
                         std::min(s, 1.0f - s), later.motion, later.spread, later.disoccluded);
            std::fprintf(file, "%s,%d,extrapolate,%.4f,%.4f,%.4f,%.6f\n", scene.name.c_str(), j, s,
                         earlier.motion, earlier.spread, earlier.disoccluded);
        }
    }
}

struct SceneSummary {
    std::string scene;
    ReportPoint interpolation, extrapolation, ffmpeg, dis, vectors;  // empty method: not run
    // The default (grid+pullpush) with and without refinement; region = where it refined.
    ReportPoint refine_on, refine_off;
    double region_on = NAN, region_off = NAN, region_share = 0.0, refine_ms = 0.0;
};

std::string refine_table(const std::vector<SceneSummary>& rows) {
    std::string text;
    char line[512];
    std::snprintf(line, sizeof line, "%-24s %8s | %8s %8s %7s | %8s %8s %7s | %9s %8s %8s\n",
                  "scene", "region %", "reg off", "reg on", "gain", "all off", "all on", "gain",
                  "refine ms", "ms off", "ms on");
    text += line;
    for (const SceneSummary& r : rows) {
        if (r.refine_on.method.empty()) continue;
        std::snprintf(line, sizeof line,
                      "%-24s %8.2f | %8.2f %8.2f %+7.2f | %8.2f %8.2f %+7.2f | %9.2f %8.2f %8.2f\n",
                      r.scene.c_str(), 100.0 * r.region_share, r.region_off, r.region_on,
                      r.region_on - r.region_off, r.refine_off.psnr, r.refine_on.psnr,
                      r.refine_on.psnr - r.refine_off.psnr, r.refine_ms, r.refine_off.ms,
                      r.refine_on.ms);
        text += line;
    }
    return text;
}

// Auto against the fixed settings of its mode on one scene.
struct AutoSummary {
    std::string scene, mode;
    ReportPoint automatic, best_fixed;
    double front_gap = 0.0;  // dB under the best point (any method) no slower than auto; 0 = on it
};

AutoSummary auto_summary(const std::string& scene, const std::string& mode,
                         const std::vector<Run>& runs) {
    AutoSummary a{scene, mode};
    for (const Run& r : runs)
        if (r.method == mode && r.setting == "auto") a.automatic = r.mean();
    const Run* best = best_of(runs, [&](const Run& r) {
        return r.method == mode && r.setting != "auto" && r.setting != "grid+telea" &&
               r.setting != "grid+pullpush+ui-warped";
    });
    if (best) a.best_fixed = best->mean();
    for (const Run& r : runs) {
        if (r.setting == "auto" || r.scores.empty()) continue;
        if (r.ours() && r.method != mode) continue;
        if (!r.ours() && mode != "interpolate") continue;
        const ReportPoint p = r.mean();
        if (p.ms <= a.automatic.ms) a.front_gap = std::max(a.front_gap, p.psnr - a.automatic.psnr);
    }
    return a;
}

std::string auto_table(const std::vector<AutoSummary>& rows) {
    std::string text;
    char line[400];
    std::snprintf(line, sizeof line, "%-24s %-11s %7s %8s | %-17s %7s %8s | %6s %6s | %5s  %s\n",
                  "scene", "auto", "PSNR", "ms", "best fixed", "PSNR", "ms", "dB", "time", "front",
                  "within 0.3 dB of the best fixed at no more time");
    text += line;
    for (const AutoSummary& r : rows) {
        if (r.automatic.method.empty() || r.best_fixed.method.empty()) continue;
        const double gain = r.automatic.psnr - r.best_fixed.psnr;
        const double ratio = r.automatic.ms / r.best_fixed.ms;
        std::string verdict = gain >= -0.3 && ratio <= 1.0 ? "yes" : "no:";
        char miss[96] = "";
        if (gain < -0.3) {
            std::snprintf(miss, sizeof miss, " %.2f dB short", -0.3 - gain);
            verdict += miss;
        }
        if (ratio > 1.0) {
            std::snprintf(miss, sizeof miss, " %.0f %% slower", 100.0 * (ratio - 1.0));
            verdict += miss;
        }
        std::snprintf(line, sizeof line,
                      "%-24s %-11s %7.2f %8.2f | %-17s %7.2f %8.2f | %+6.2f %5.2fx | %5.2f  %s\n",
                      r.scene.c_str(), r.mode.c_str(), r.automatic.psnr, r.automatic.ms,
                      r.best_fixed.setting.c_str(), r.best_fixed.psnr, r.best_fixed.ms, gain, ratio,
                      r.front_gap, verdict.c_str());
        text += line;
    }
    return text;
}

std::string summary_table(const std::vector<SceneSummary>& rows) {
    std::string text;
    char line[512];
    std::snprintf(line, sizeof line,
                  "%-24s %-18s %7s %8s | %-17s %7s %8s | %7s %8s | %7s %8s | %7s %8s | %7s  %s\n",
                  "scene", "best interpolation", "PSNR", "ms", "best extrapolation", "PSNR", "ms",
                  "ffmpeg", "ms", "DIS", "ms", "vectors", "ms", "margin",
                  ">=3 dB over the better of ffmpeg and DIS, faster than both");
    text += line;
    auto value = [](const ReportPoint& p, bool ms) {
        char b[32];
        if (p.method.empty()) return std::string("-");
        std::snprintf(b, sizeof b, "%.2f", ms ? p.ms : p.psnr);
        return std::string(b);
    };
    for (const SceneSummary& r : rows) {
        const bool has_ffmpeg = !r.ffmpeg.method.empty(), has_dis = !r.dis.method.empty();
        double peer_db = -INFINITY, peer_ms = INFINITY;
        if (has_ffmpeg)
            peer_db = std::max(peer_db, r.ffmpeg.psnr), peer_ms = std::min(peer_ms, r.ffmpeg.ms);
        if (has_dis) peer_db = std::max(peer_db, r.dis.psnr), peer_ms = std::min(peer_ms, r.dis.ms);
        std::string margin = "-", verdict = "no peer";
        if (has_ffmpeg || has_dis) {
            const double m = r.interpolation.psnr - peer_db;
            char b[32];
            std::snprintf(b, sizeof b, "%+.2f", m);
            margin = b;
            const bool enough = m >= 3.0, faster = r.interpolation.ms < peer_ms;
            verdict = enough && faster ? "yes"
                      : enough         ? "no: slower than a peer"
                      : faster         ? "no: margin under 3 dB"
                                       : "no: margin under 3 dB and slower";
            if (!(has_ffmpeg && has_dis)) verdict += " (one peer only)";
        }
        std::snprintf(
            line, sizeof line,
            "%-24s %-18s %7s %8s | %-17s %7s %8s | %7s %8s | %7s %8s | %7s %8s | %7s  %s\n",
            r.scene.c_str(), r.interpolation.setting.c_str(), value(r.interpolation, false).c_str(),
            value(r.interpolation, true).c_str(), r.extrapolation.setting.c_str(),
            value(r.extrapolation, false).c_str(), value(r.extrapolation, true).c_str(),
            value(r.ffmpeg, false).c_str(), value(r.ffmpeg, true).c_str(),
            value(r.dis, false).c_str(), value(r.dis, true).c_str(),
            value(r.vectors, false).c_str(), value(r.vectors, true).c_str(), margin.c_str(),
            verdict.c_str());
        text += line;
    }
    return text;
}

// The report's opening: what was run and how it is timed.
void describe(const BenchOptions& job, int w, int h, const std::string& device, Report& report) {
    report.title = "reprise bench fruc: frame-rate upconversion, error against run time";
    const int synthesized = (job.frames - 1) * (job.factor - 1);
    char text[2048];
    std::snprintf(
        text, sizeof text,
        "x%d upconversion of %d input frames at 30 Hz (%dx%d, anti-aliasing %d samples), "
        "renderer %s. Each method's %d in-between frames are compared with frames rendered at "
        "%d Hz (display values: PSNR, SSIM, LDR-FLIP); the input frames passed through are not "
        "scored.",
        job.factor, job.frames, w, h, job.aa, device.c_str(), synthesized, 30 * job.factor);
    report.paragraphs.push_back(text);
    if (!job.in.empty())
        report.paragraphs.push_back(
            "Sequence folders (--in) keep their own size and length: the summary says each.");
    std::snprintf(
        text, sizeof text,
        "ms = wall-clock milliseconds per synthesized frame on this machine (%d threads for "
        "reprise's loops), the fastest of %d runs (machines are shared and noisy). Ours: "
        "FrameRateConverter::send() alone, from G-buffers in memory. "
        "opencv-dis: DIS flow (preset MEDIUM) both ways per input pair, shared by its in-between "
        "frames, plus remap and blend of 8-bit frames. ffmpeg-minterpolate (mi_mode=mci): the "
        "whole ffmpeg run divided by the frames it synthesized, including process start, raw "
        "video I/O and RGB/YUV conversion. grid+telea: the grid warp without fill plus "
        "cv::inpaint (Telea) of its holes. rendered-vectors: the plain use of the rendered motion "
        "anyone could write (both frames splatted one pixel each along their vectors, nearest "
        "wins, blended on the same surface, holes by Telea). Scenes marked (held) are glTF "
        "sample models or sequence folders (--in) no default was tuned on.",
        thread_count(), job.repeat);
    report.paragraphs.push_back(text);
}

// Every method on one scene: our settings (with grid+telea beside those that ask for it), the
// UI baked into the colour when the scene has one, and the peers.
Status run_methods(SceneFrames& scene, const std::string& scene_dir,
                   const std::vector<Setting>& settings, const BenchOptions& job, bool has_ffmpeg,
                   std::map<std::string, warp::FrucCounters>& auto_counts, std::vector<Run>& runs) {
    runs.reserve(settings.size() + 3);
    for (const Setting& setting : settings) {
        runs.push_back({setting.method, setting.setting});
        Run telea{"interpolate", "grid+telea"};
        warp::FrucCounters counters;
        REPRISE_TRY(run_ours(scene, setting, job.repeat, runs.back(),
                             setting.with_telea ? &telea : nullptr, counters));
        progress(scene.name, runs.back());
        if (setting.setting == "auto")
            std::fprintf(stderr, "[fruc] %s: %s auto chose / left out:\n%s", scene.name.c_str(),
                         setting.method.c_str(), auto_choice_summary(counters).c_str());
        if (setting.setting == "auto") auto_counts[scene.name + " " + setting.method] = counters;
        if (setting.with_telea) {
            runs.push_back(std::move(telea));
            progress(scene.name, runs.back());
        }
    }
    if (!scene.input[0].ui.empty()) {
        // The same frames with the UI baked into the colour: warped along with the scene.
        SceneFrames baked = scene;
        for (Frame& f : baked.input) {
            composite_ui(f.color.view(), f.ui.view(), f.color.view());
            f.ui.clear();
        }
        Setting plain{"interpolate", "grid+pullpush+ui-warped"};
        const Status parsed = parse_fruc_options("interpolate", "grid", "pullpush", plain.options);
        REPRISE_ASSERT(parsed.ok());
        runs.push_back({plain.method, plain.setting});
        warp::FrucCounters ignored;
        REPRISE_TRY(run_ours(baked, plain, job.repeat, runs.back(), nullptr, ignored));
        progress(scene.name, runs.back());
    }
    runs.push_back({kDis, "medium"});
    run_dis(scene, job.repeat, runs.back());
    progress(scene.name, runs.back());
    runs.push_back({kVectors, "splat+telea"});
    run_vectors(scene, job.repeat, runs.back());
    progress(scene.name, runs.back());
    if (has_ffmpeg) {
        Run ffmpeg{kFfmpeg, "mci"};
        Status ran = run_ffmpeg(scene, scene_dir, job.repeat, ffmpeg);
        if (ran.ok()) {
            runs.push_back(std::move(ffmpeg));
            progress(scene.name, runs.back());
        } else {
            std::printf("note: %s: ffmpeg peer skipped: %s\n", scene.name.c_str(),
                        ran.message().c_str());
        }
    }
    return {};
}

// The scene's row of the summary tables; `interpolation` and `peer` get its best interpolation
// setting and its best peer (null when none ran).
SceneSummary summarize(const std::string& scene_name, const SceneFrames& scene,
                       const std::vector<Run>& runs, std::vector<AutoSummary>& autos,
                       const Run*& interpolation, const Run*& peer) {
    SceneSummary row{scene.name + (is_held_out(scene_name) ? " (held)" : "")};
    interpolation = best_of(runs, [](const Run& r) {
        return r.method == "interpolate" && r.setting != "grid+telea" && r.setting != "auto" &&
               r.setting != "grid+pullpush+ui-warped";
    });
    const Run* extrapolation = best_of(
        runs, [](const Run& r) { return r.method == "extrapolate" && r.setting != "auto"; });
    for (const char* mode : {"interpolate", "extrapolate"})
        autos.push_back(auto_summary(row.scene, mode, runs));
    peer = best_of(runs, [](const Run& r) { return !r.ours(); });
    if (interpolation) row.interpolation = interpolation->mean();
    if (extrapolation) row.extrapolation = extrapolation->mean();
    for (const Run& r : runs) {
        if (r.method == "interpolate" && r.setting == "grid+pullpush") {
            row.refine_on = r.mean();
            row.region_on = r.region_psnr();
            row.refine_ms = r.refine_ms;
            row.region_share = double(r.region_pixels) /
                               (double(scene.input[0].width()) * scene.input[0].height() *
                                double(std::max<std::size_t>(1, r.scores.size())));
        }
        if (r.setting == kRefineOff) {
            row.refine_off = r.mean();
            row.region_off = r.region_psnr();
        }
        if (r.method == kFfmpeg) row.ffmpeg = r.mean();
        if (r.method == kDis) row.dis = r.mean();
        if (r.method == kVectors) row.vectors = r.mean();
    }
    return row;
}

}  // namespace

Status bench_fruc(const BenchOptions& job) {
    if (job.factor < 2 || job.factor > 16)
        return Status::error("bench fruc: --factor must be in 2..16");
    if (job.frames < 2 || job.frames > 1000)
        return Status::error("bench fruc: --frames must be in 2..1000");
    if (job.repeat < 1 || job.repeat > 100)
        return Status::error("bench fruc: --repeat must be in 1..100");
    if (!server::aa_samples_valid(job.aa))
        return Status::error("bench fruc: --aa must be 1, 2, 4, 8 or 16");
    int w = 0, h = 0;
    REPRISE_TRY(parse_size(job.size, w, h));
    const std::vector<std::string> scenes = scene_list(job.scenes, job.in);
    const std::string out_dir = job.out.empty() ? "out/bench-fruc" : job.out;
    std::error_code ec;
    fs::create_directories(out_dir, ec);
    if (ec) return Status::error(out_dir + ": cannot create the folder: " + ec.message());

    std::unique_ptr<server::Renderer> renderer;
    REPRISE_TRY(server::Renderer::create(renderer));
    const bool has_ffmpeg = ffmpeg_has_minterpolate();
    if (!has_ffmpeg)
        std::printf("note: ffmpeg with the minterpolate filter not found; that peer is skipped\n");
    const std::vector<Setting> settings = fruc_settings(job.quick);

    const std::string csv_path = out_dir + "/fruc.csv",
                      summary_path = out_dir + "/fruc_summary.csv";
    CsvFile csv, summary_csv;
    REPRISE_TRY(csv.open(csv_path, kErrorTimeColumns));
    REPRISE_TRY(summary_csv.open(summary_path, "scene,method,setting,frames,psnr,ssim,flip,ms"));
    CsvFile predictors_csv;
    REPRISE_TRY(predictors_csv.open(out_dir + "/fruc_predictors.csv",
                                    "scene,frame,mode,distance,motion,spread,disoccluded"));
    std::map<std::string, warp::FrucCounters> auto_counts;
    std::vector<AutoSummary> autos;

    Report report;
    describe(job, w, h, renderer->device(), report);
    char text[2048];
    // Size and length of what ran, with the scenes of each (sequence folders keep their own).
    std::vector<std::pair<std::string, std::string>> shapes;
    std::vector<SceneSummary> summaries;

    Status failure;
    for (const std::string& scene_name : scenes) {
        SceneFrames scene;
        const std::string source =
            is_sequence(scene_name) ? scene_name.substr(std::strlen(kSequencePrefix)) : scene_name;
        scene.name = fs::path(source).filename().string();
        if (!is_sequence(scene_name)) scene.name = fs::path(source).stem().string();
        const std::string scene_dir = out_dir + "/" + scene.name;
        fs::create_directories(scene_dir, ec);
        if (ec) return Status::error(scene_dir + ": cannot create the folder: " + ec.message());
        failure = is_sequence(scene_name)
                      ? read_scene(source, job.frames, job.factor, scene)
                      : render_scene(*renderer, scene_name, job.frames, job.factor, w, h, job.aa,
                                     job.exr ? scene_dir : std::string(), scene);
        if (!failure.ok()) break;
        write_predictors(predictors_csv.file(), scene);
        const std::string shape =
            std::to_string(scene.input[0].width()) + "x" + std::to_string(scene.input[0].height()) +
            ", " + std::to_string(scene.input.size()) + " input frames, " +
            std::to_string((int(scene.input.size()) - 1) * (scene.factor - 1)) +
            " scored frames per method";
        auto same = std::find_if(shapes.begin(), shapes.end(),
                                 [&](const auto& s) { return s.first == shape; });
        if (same == shapes.end())
            shapes.emplace_back(shape, scene.name);
        else
            same->second += ", " + scene.name;

        std::vector<Run> runs;
        failure = run_methods(scene, scene_dir, settings, job, has_ffmpeg, auto_counts, runs);
        if (!failure.ok()) break;

        ReportSection section{scene.name};
        for (const server::SceneInfo& info : server::builtin_scenes())
            if (scene_name == info.name) section.note = info.stresses;
        if (is_held_out(scene_name))
            section.note =
                is_sequence(scene_name)
                    ? "held out: a sequence folder (" + source + "): input/ at 30 Hz, truth/ at " +
                          std::to_string(30 * job.factor) + " Hz"
                    : "held out: a glTF sample model no default was tuned on (" + scene_name + ")";
        for (const Run& run : runs) {
            for (const Score& s : run.scores)
                csv.error_row(scene.name, run.method, run.setting, s.frame, s.error, s.ms);
            ReportPoint p = run.mean();
            std::fprintf(summary_csv.file(), "%s,%s,%s,%zu,%.4f,%.6f,%.6f,%.4f\n",
                         scene.name.c_str(), run.method.c_str(), run.setting.c_str(),
                         run.scores.size(), p.psnr, p.ssim, p.flip, p.ms);
            section.points.push_back(p);
        }

        const Run *interpolation = nullptr, *peer = nullptr;
        const SceneSummary row = summarize(scene_name, scene, runs, autos, interpolation, peer);
        summaries.push_back(row);
        if (interpolation) {
            const std::string picture = scene.name + "/worst_frame.png";
            failure = comparison_picture(scene, *interpolation, peer, out_dir + "/" + picture);
            if (!failure.ok()) break;
            section.images.push_back(
                {picture,
                 "The lowest-PSNR frame of the best interpolation setting (" +
                     interpolation->setting + ", frame " +
                     std::to_string(interpolation->worst_frame) + ") beside the ground truth" +
                     (peer ? " and the better peer (" + peer->method + ")" : std::string()) +
                     "; below, the window where ours differs most from the truth, enlarged."});
        }
        report.sections.push_back(std::move(section));
        csv.flush();
        summary_csv.flush();
        predictors_csv.flush();
    }
    REPRISE_TRY(failure);

    std::string table = summary_table(summaries), shape;
    for (const auto& [what, names] : shapes)
        shape += (shape.empty() ? "" : "; ") + what + (shapes.size() > 1 ? " (" + names + ")" : "");
    std::snprintf(text, sizeof text,
                  "fruc x%d, %s; PSNR in dB, ms per synthesized frame; margin = best "
                  "interpolation - better peer\n",
                  job.factor, shape.c_str());
    const std::string refinement =
        "\nmotion refinement (default grid+pullpush, refine on vs off): region = pixels of the "
        "tiles where\nthe sides warped along rendered motion disagree (share of scored pixels), "
        "PSNR there and over\nwhole frames; refine ms = survey + flow + choice per made frame\n" +
        refine_table(summaries);
    table += refinement;
    std::string automatic =
        "\nauto (--warp auto --fill auto, cheapest within 0.25 dB of the best expected) against "
        "the best fixed setting of its mode; front = dB under the best point no slower than auto "
        "(0: on the Pareto front)\n" +
        auto_table(autos) + "auto chose / left out (frames):\n";
    for (const auto& [name, counters] : auto_counts)
        automatic += "  " + name + "\n" + auto_choice_summary(counters);
    table += automatic;
    report.preformatted = std::string(text) + table;
    const std::string html_path = out_dir + "/index.html";
    REPRISE_TRY(write_html_report(html_path, report));
    std::printf("%s%s", text, table.c_str());
    std::printf("report: %s\nrows: %s\nmeans: %s\n", html_path.c_str(), csv_path.c_str(),
                summary_path.c_str());
    return {};
}

}  // namespace reprise::cli
