// reprise bench fruc — frame-rate upconversion error against run time: every mode, warp and fill
// beside ffmpeg's minterpolate, OpenCV DIS flow and Telea inpainting, on the same rendered frames.
#include <algorithm>
#include <cmath>
#include <cstdio>
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

bool is_held_out(const std::string& scene) { return scene.rfind(kHeldOutDir, 0) == 0; }

// The --scenes list with `held-out` expanded; empty = every built-in scene and the held-out ones.
std::vector<std::string> scene_list(const std::string& spec) {
    std::vector<std::string> given = split_list(spec), scenes;
    if (given.empty()) {
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
    return scenes;
}

struct Setting {
    std::string method, setting;
    warp::FrucOptions options;
    bool with_telea = false;  // also score Telea inpainting of this run's holes (fill none)
};

std::vector<Setting> fruc_settings(bool quick) {
    std::vector<Setting> settings;
    auto add = [&](const std::string& mode, const std::string& warp_name, const std::string& fill) {
        Setting s{mode, warp_name + "+" + fill};
        Status parsed = parse_fruc_options(mode, warp_name, fill, s.options);
        REPRISE_ASSERT(parsed.ok());
        s.with_telea = !quick && mode == "interpolate" && warp_name == "grid" && fill == "none";
        settings.push_back(s);
    };
    if (quick) {
        add("interpolate", "grid", "pullpush");
        // The grid's other colour fetch, beside the default one.
        add("interpolate", warp::FrucOptions{}.grid.bicubic ? "grid-bilinear" : "grid-bicubic",
            "pullpush");
        add("interpolate", "reverse", "pullpush");
        add("interpolate", "splat", "none");
        add("extrapolate", "grid", "pullpush");
        return settings;
    }
    for (const char* mode : {"interpolate", "extrapolate"})
        for (const char* warp_name : {"reverse", "splat", "grid"})
            for (const char* fill : {"pullpush", "andreev", "none"}) add(mode, warp_name, fill);
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
    const server::RenderSettings settings{.width = w, .height = h, .aa_samples = aa};
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
        visualize_color(out.input[i].color.view(), out.input_shown[i].view());
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
        reprise::to_display(truth.color.view(), out.truth[j].view());
        std::fprintf(stderr, "\r[fruc] %s: rendering truth %d/%d   ", out.name.c_str(), j,
                     out.last());
    }
    std::fprintf(stderr, "\n");
    return {};
}

// Times send() alone; each frame it made gets an equal share of that time, the fastest of
// `repeat` runs over the sequence. Frames are scored on the first run.
Status run_ours(const SceneFrames& scene, const Setting& setting, int repeat, Run& run,
                Run* telea) {
    const int w = scene.input[0].width(), h = scene.input[0].height();
    Frame out;
    Image<glm::vec3> display(w, h);
    Image<uint8_t> holes(w, h);
    std::map<int, double> send_ms, telea_ms;
    for (int rep = 0; rep < repeat; ++rep) {
        warp::FrameRateConverter converter(scene.factor, setting.options);
        int index = 0;
        for (const Frame& input : scene.input) {
            auto start = BenchClock::now();
            REPRISE_TRY(converter.send(input));
            const double ms = ms_since(start);
            std::vector<int> made;
            while (converter.receive(out)) {
                const int j = index++;
                if (j % scene.factor == 0) continue;  // an input passed through
                made.push_back(j);
                if (!scene.scored(j)) continue;  // beyond the last input: no truth to compare
                if (rep == 0 || telea) to_display(out.color.view(), display.view());
                if (rep == 0) record(run, j, display, scene.truth[j], 0.0, false);
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

struct SceneSummary {
    std::string scene;
    ReportPoint interpolation, extrapolation, ffmpeg, dis, vectors;  // empty method: not run
};

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
    const std::vector<std::string> scenes = scene_list(job.scenes);
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

    Report report;
    report.title = "reprise bench fruc: frame-rate upconversion, error against run time";
    const int synthesized = (job.frames - 1) * (job.factor - 1);
    char text[2048];
    std::snprintf(
        text, sizeof text,
        "x%d upconversion of %d input frames at 30 Hz (%dx%d, anti-aliasing %d samples), "
        "renderer %s. Each method's %d in-between frames are compared with frames rendered at "
        "%d Hz (display values: PSNR, SSIM, LDR-FLIP); the input frames passed through are not "
        "scored.",
        job.factor, job.frames, w, h, job.aa, renderer->device().c_str(), synthesized,
        30 * job.factor);
    report.paragraphs.push_back(text);
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
        "sample models no default was tuned on.",
        thread_count(), job.repeat);
    report.paragraphs.push_back(text);
    std::vector<SceneSummary> summaries;

    Status failure;
    for (const std::string& scene_name : scenes) {
        SceneFrames scene;
        scene.name = fs::path(scene_name).stem().string();
        const std::string scene_dir = out_dir + "/" + scene.name;
        fs::create_directories(scene_dir, ec);
        if (ec) return Status::error(scene_dir + ": cannot create the folder: " + ec.message());
        failure = render_scene(*renderer, scene_name, job.frames, job.factor, w, h, job.aa,
                               job.exr ? scene_dir : std::string(), scene);
        if (!failure.ok()) break;

        std::vector<Run> runs;
        runs.reserve(settings.size() + 3);
        for (const Setting& setting : settings) {
            runs.push_back({setting.method, setting.setting});
            Run telea{"interpolate", "grid+telea"};
            failure = run_ours(scene, setting, job.repeat, runs.back(),
                               setting.with_telea ? &telea : nullptr);
            if (!failure.ok()) break;
            progress(scene.name, runs.back());
            if (setting.with_telea) {
                runs.push_back(std::move(telea));
                progress(scene.name, runs.back());
            }
        }
        if (!failure.ok()) break;
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

        ReportSection section{scene.name};
        for (const server::SceneInfo& info : server::builtin_scenes())
            if (scene_name == info.name) section.note = info.stresses;
        if (is_held_out(scene_name))
            section.note =
                "held out: a glTF sample model no default was tuned on (" + scene_name + ")";
        for (const Run& run : runs) {
            for (const Score& s : run.scores)
                csv.error_row(scene.name, run.method, run.setting, s.frame, s.error, s.ms);
            ReportPoint p = run.mean();
            std::fprintf(summary_csv.file(), "%s,%s,%s,%zu,%.4f,%.6f,%.6f,%.4f\n",
                         scene.name.c_str(), run.method.c_str(), run.setting.c_str(),
                         run.scores.size(), p.psnr, p.ssim, p.flip, p.ms);
            section.points.push_back(p);
        }

        SceneSummary row{scene.name + (is_held_out(scene_name) ? " (held)" : "")};
        const Run* interpolation = best_of(runs, [](const Run& r) {
            return r.method == "interpolate" && r.setting != "grid+telea";
        });
        const Run* extrapolation =
            best_of(runs, [](const Run& r) { return r.method == "extrapolate"; });
        const Run* peer = best_of(runs, [](const Run& r) { return !r.ours(); });
        if (interpolation) row.interpolation = interpolation->mean();
        if (extrapolation) row.extrapolation = extrapolation->mean();
        for (const Run& r : runs) {
            if (r.method == kFfmpeg) row.ffmpeg = r.mean();
            if (r.method == kDis) row.dis = r.mean();
            if (r.method == kVectors) row.vectors = r.mean();
        }
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
    }
    REPRISE_TRY(failure);

    std::string table = summary_table(summaries);
    std::snprintf(
        text, sizeof text,
        "fruc x%d, %dx%d, %d input frames, %d scored frames per method; PSNR in dB, ms per "
        "synthesized frame; margin = best interpolation - better peer\n",
        job.factor, w, h, job.frames, synthesized);
    report.preformatted = std::string(text) + table;
    const std::string html_path = out_dir + "/index.html";
    REPRISE_TRY(write_html_report(html_path, report));
    std::printf("%s%s", text, table.c_str());
    std::printf("report: %s\nrows: %s\nmeans: %s\n", html_path.c_str(), csv_path.c_str(),
                summary_path.c_str());
    return {};
}

}  // namespace reprise::cli
