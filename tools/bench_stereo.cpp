// reprise bench stereo: the synthesized eye against the rendered one, beside naive DIBR peers and
// the renderer's own time for the second eye, on every built-in scene.
//
// OUT/stereo.csv has the project's standard columns scene,method,setting,frame,psnr,ssim,flip,ms.
// Every row is repeated with the setting suffixed "+disoccluded": the same method scored only on
// the pixels the left eye does not see (no source pixel lands there under a nearest-pixel splat),
// ms repeated; PSNR is NaN on a frame without such pixels. OUT/index.html is the error-against-
// run-time report (report_html), OUT/SCENE/worst_frame.png the worst frame of our best setting.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "args.hpp"
#include "bench.hpp"
#include "bench_report.hpp"
#include "peers.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/core/metrics.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/core/visualize.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "reprise/stereo/alternate.hpp"
#include "reprise/stereo/rig.hpp"
#include "reprise/stereo/synthesize.hpp"
#include "timing.hpp"

namespace reprise::cli {

namespace {

namespace fs = std::filesystem;

// Issue 4's targets.
constexpr double kPairRatioTarget = 0.6;    // (one render + synthesis) / (two renders)
constexpr double kSynthesisTargetMs = 8.0;  // at 1920x1080

const char* const kOurs = "ours";
const char* const kSplatPeer = "dibr-splat";  // forward splat, footprint 1, no fill
const char* const kRemapPeer = "cv-remap";    // backward remap by the left eye's disparity
const char* const kCopyPeer = "copy-left-eye";
const char* const kRender = "render";        // the renderer's second eye (the truth)
const char* const kAlternate = "alternate";  // one eye rendered per frame, the other made

// Naive backward DIBR peer: right(x) = left(x + d(x)), d from the left eye's own depth at x.
void remap_by_disparity(const Frame& left, const stereo::StereoRig& rig, Image<glm::vec4>& out) {
    const int w = left.width(), h = left.height();
    cv::Mat map_x(h, w, CV_32F), map_y(h, w, CV_32F);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float z = left.depth(x, y);
            const float d =
                z > 0.0f ? stereo::disparity_px(rig, left.camera.projection, w, z) : 0.0f;
            map_x.at<float>(y, x) = float(x) + (std::isfinite(d) ? d : 0.0f);
            map_y.at<float>(y, x) = float(y);
        }
    out.resize(w, h);
    cv::Mat src(h, w, CV_32FC4, const_cast<glm::vec4*>(left.color.data()));
    cv::Mat dst(h, w, CV_32FC4, out.data());
    cv::remap(src, dst, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
}

struct Score {
    int frame = 0;
    ImageError all, disoccluded;
    double ms = 0.0;
};

struct Run {
    std::string method, setting;
    std::vector<Score> scores;
    std::map<int, Image<Rgb8>> shown;  // per frame, as displayed (for the worst-frame picture)
    bool ours() const { return method == kOurs; }
    // Means over frames; `disoccluded` over the frames that have such pixels.
    ReportPoint mean(bool disoccluded = false) const {
        ReportPoint p{method, setting};
        std::size_t n = 0;
        for (const Score& s : scores) {
            const ImageError& e = disoccluded ? s.disoccluded : s.all;
            if (std::isnan(e.psnr)) continue;
            p.psnr += e.psnr, p.ssim += e.ssim, p.flip += e.flip, p.ms += s.ms, ++n;
        }
        if (n == 0) return {method, setting, NAN, NAN, NAN, NAN};
        p.psnr /= double(n), p.ssim /= double(n), p.flip /= double(n), p.ms /= double(n);
        return p;
    }
    double mean_ms() const {
        double sum = 0.0;
        for (const Score& s : scores) sum += s.ms;
        return scores.empty() ? NAN : sum / double(scores.size());
    }
};

// Our best setting's lowest-PSNR frame beside the rendered eye and the best peer, full frames
// over the window where ours errs most, enlarged.
Status worst_picture(const Run& ours, const Run& truth, const Run* peer, const std::string& path) {
    int j = -1;
    double worst = INFINITY;
    for (const Score& s : ours.scores)
        if (j < 0 || s.all.psnr < worst) j = s.frame, worst = s.all.psnr;
    if (j < 0) return {};
    const Image<Rgb8>& a = ours.shown.at(j);
    const Image<Rgb8>& t = truth.shown.at(j);
    std::vector<Image<Rgb8>> images = {a, t};
    std::vector<std::string> labels = {"ours " + ours.setting + " " + db(worst),
                                       "rendered right eye, frame " + std::to_string(j)};
    if (peer && peer->shown.count(j)) {
        images.push_back(peer->shown.at(j));
        std::string label = peer->method + " " + peer->setting;
        for (const Score& s : peer->scores)
            if (s.frame == j) label += " " + db(s.all.psnr);
        labels.push_back(label);
    }
    return write_worst_window_sheet(path, std::move(images), std::move(labels), t, 640);
}

struct SceneSummary {
    std::string scene;
    ReportPoint best, best_dis;        // our best setting (by PSNR on all pixels)
    ReportPoint fastest, fastest_dis;  // our fastest setting (mean ms)
    double splat = NAN, telea = NAN, remap = NAN, copy = NAN;  // peers' PSNR, all pixels
    double render_left_ms = NAN, render_right_ms = NAN;
    double disoccluded_fraction = NAN;
    // Eye alternation: the made eye (right on even frames, left on odd) and its cost.
    ReportPoint alternate;
    double alternate_render_ms = NAN;         // the rendered eye, mean over frames
    double fixed = NAN, fixed_history = NAN;  // grid+pullpush without / with the history
    double alternate_ratio() const {
        return (alternate_render_ms + alternate.ms) / (render_left_ms + render_right_ms);
    }
    double ratio(const ReportPoint& ours) const {
        return (render_left_ms + ours.ms) / (render_left_ms + render_right_ms);
    }
};

std::string summary_table(const std::vector<SceneSummary>& rows, bool full_hd) {
    std::string out;
    char line[512];
    std::snprintf(line, sizeof line, "%-9s %-22s %7s %7s %8s | %7s %7s %7s %7s | %9s %6s %6s %s\n",
                  "scene", "ours best", "psnr", "psnr_d", "ms", "splat", "telea", "remap", "copyL",
                  "render_ms", "dis%", "ratio", "targets (ratio<=0.6, ms<=8 @1080p)");
    out += line;
    for (const SceneSummary& r : rows)
        for (bool fastest : {false, true}) {
            const ReportPoint& p = fastest ? r.fastest : r.best;
            const ReportPoint& d = fastest ? r.fastest_dis : r.best_dis;
            const double ratio = r.ratio(p);
            std::string verdict =
                std::isnan(ratio)
                    ? "ratio n/a (read, not rendered)"
                    : std::string("ratio ") + (ratio <= kPairRatioTarget ? "met" : "NOT met");
            verdict += full_hd
                           ? std::string(", ms ") + (p.ms <= kSynthesisTargetMs ? "met" : "NOT met")
                           : std::string(", ms n/a (not 1920x1080)");
            const std::string label = (fastest ? "  fastest: " : "") + p.setting;
            std::snprintf(
                line, sizeof line,
                "%-9s %-22s %7.2f %7.2f %8.2f | %7.2f %7.2f %7.2f %7.2f | %9.2f %6.2f %6.3f %s\n",
                fastest ? "" : r.scene.c_str(), label.c_str(), p.psnr, d.psnr, p.ms, r.splat,
                r.telea, r.remap, r.copy, r.render_right_ms, 100.0 * r.disoccluded_fraction, ratio,
                verdict.c_str());
            out += line;
        }
    return out;
}

std::string alternation_table(const std::vector<SceneSummary>& rows) {
    std::string out;
    char line[512];
    std::snprintf(line, sizeof line, "%-9s %9s %7s %9s %9s %8s %9s %6s\n", "scene", "alternate",
                  "flip", "grid+pp", "+history", "ms", "render_ms", "ratio");
    out += line;
    for (const SceneSummary& r : rows) {
        std::snprintf(line, sizeof line, "%-9s %9.2f %7.4f %9.2f %9.2f %8.2f %9.2f %6.3f\n",
                      r.scene.c_str(), r.alternate.psnr, r.alternate.flip, r.fixed, r.fixed_history,
                      r.alternate.ms, r.alternate_render_ms, r.alternate_ratio());
        out += line;
    }
    return out;
}

// The report's opening: what was compared and how it is timed.
void describe(const stereo::StereoRig& rig, int w, int h, int frames, int repeat,
              const std::string& device, Report& report) {
    report.title = "reprise bench stereo: the second eye, error against run time";
    char text[2048];
    std::snprintf(
        text, sizeof text,
        "The right eye synthesized from the rendered left eye (parallel rig, ipd %.3f) compared "
        "with "
        "the right eye rendered, %dx%d, %d frames per scene from t = 10/30 s, renderer %s. Display "
        "values: PSNR, SSIM, LDR-FLIP. Each scene has two plots: all pixels, and only the "
        "disoccluded pixels (those no left-eye pixel lands on under a nearest-pixel splat).",
        rig.ipd, w, h, frames, device.c_str());
    report.paragraphs.push_back(text);
    std::snprintf(
        text, sizeof text,
        "ms = wall-clock milliseconds per synthesized eye on this machine (%d threads), the "
        "fastest "
        "of %d runs. ours: StereoSynthesizer::synthesize() from the left eye's colour + depth in "
        "memory, per warp (adaptive grid, splat) and fill (none, pull-push, Andreev); "
        "+history also warps the previous frame's rendered right eye (as when the rendered eye "
        "alternates per frame). Peers: dibr-splat = forward splat of footprint 1 with a depth test "
        "and no fill, and the same with its holes filled by cv::inpaint Telea on display values "
        "(dibr-splat telea; ms both); cv-remap = cv::remap of the left eye by its own disparity "
        "(bilinear); "
        "copy-left-eye = the left eye as it is (ms = the copy). render = the renderer's time for "
        "the second eye (PSNR +inf by definition, drawn on the top edge). alternate = eye "
        "alternation: each frame renders one eye (left on even frames) and makes the other with "
        "EyeAlternation, the made eye scored against its rendered twin (ms: the synthesis with "
        "the copy it keeps as history). Sequence folders (--in: input/ the left eye, right/ the "
        "right one, scripts/blender-scenes --stereo) are read, not rendered: no render times, "
        "the history is the right eye of the frame before, and the eyes stand as far apart as "
        "their cameras.",
        thread_count(), repeat);
    report.paragraphs.push_back(text);
}

// The fastest of `times` runs of `run`, in ms.
template <class Run>
double fastest_ms(int times, Run&& run) {
    double ms = 1e30;
    for (int r = 0; r < times; ++r) {
        auto begin = BenchClock::now();
        run();
        ms = std::min(ms, ms_since(begin));
    }
    return ms;
}

struct OurSetting {
    std::string setting;
    stereo::StereoOptions options;
    bool history = false;
};
// Every warp with every fill, and the default with history.
std::vector<OurSetting> our_settings() {
    std::vector<OurSetting> settings;
    for (auto [warp_name, warp] : {std::pair{"grid", stereo::StereoWarp::Grid},
                                   std::pair{"splat", stereo::StereoWarp::Splat}})
        for (auto [fill_name, fill] : {std::pair{"none", stereo::StereoFill::None},
                                       std::pair{"pullpush", stereo::StereoFill::PullPush},
                                       std::pair{"andreev", stereo::StereoFill::Andreev},
                                       std::pair{"patch", stereo::StereoFill::Patch}})
            settings.push_back(
                {std::string(warp_name) + "+" + fill_name, {.warp = warp, .fill = fill}});
    // The other colour fetch of the grid (bicubic by default), with the default fill.
    stereo::StereoOptions other_fetch;
    other_fetch.grid.bicubic = !other_fetch.grid.bicubic;
    settings.push_back(
        {other_fetch.grid.bicubic ? "grid-bicubic+pullpush" : "grid-bilinear+pullpush",
         other_fetch});
    // The default in linear light (StereoOptions::perceptual off).
    settings.push_back({"grid+pullpush-linear", {.perceptual = false}});
    settings.push_back({"grid+pullpush+history", {}, true});
    return settings;
}

// One eye of the path's centre camera at time t, rendered; the fastest of `times` runs in `ms`.
Status render_eye(server::Renderer& renderer, const server::Scene& scene,
                  const server::CameraPath& path, const stereo::StereoRig& rig, int w, int h,
                  double t, stereo::Eye e, int times, Frame& out, double& ms) {
    const double fps = 30.0;
    const server::Instant now = server::instant_on_path(path, scene, t, w, h);
    const server::Instant before = server::instant_on_path(path, scene, t - 1.0 / fps, w, h);
    Camera centre;
    centre.view = now.view;
    centre.projection = now.projection;
    centre.prev_view = before.view;
    centre.prev_projection = before.projection;
    const stereo::EyeCameras eyes = stereo::eye_cameras(centre, rig);
    server::Instant a = now, b = before;
    a.view = eyes[e].view;
    a.projection = eyes[e].projection;
    b.view = eyes[e].prev_view;
    b.projection = eyes[e].prev_projection;
    Status status;
    ms = fastest_ms(times, [&] {
        if (status.ok()) status = renderer.render(scene, a, b, {.width = w, .height = h}, out);
    });
    return status;
}

// The scene's summary row: our best and fastest settings, the peers, the renders; `best` and
// `peer` get our best run and the best peer's.
SceneSummary summarize(const std::string& name, const std::vector<Run>& runs, double render_left,
                       double render_right, double dis_fraction, const Run*& best,
                       const Run*& peer) {
    SceneSummary row{name};
    best = nullptr;
    const Run* fastest = nullptr;
    peer = nullptr;
    for (const Run& run : runs) {
        if (run.ours() && (!best || run.mean().psnr > best->mean().psnr)) best = &run;
        if (run.ours() && (!fastest || run.mean_ms() < fastest->mean_ms())) fastest = &run;
        if (!run.ours() && run.method != kRender && (!peer || run.mean().psnr > peer->mean().psnr))
            peer = &run;
        if (run.method == kSplatPeer && run.setting == "nofill") row.splat = run.mean().psnr;
        if (run.method == kSplatPeer && run.setting == "telea") row.telea = run.mean().psnr;
        if (run.method == kRemapPeer) row.remap = run.mean().psnr;
        if (run.method == kCopyPeer) row.copy = run.mean().psnr;
        if (run.ours() && run.setting == "grid+pullpush") row.fixed = run.mean().psnr;
        if (run.ours() && run.setting == "grid+pullpush+history")
            row.fixed_history = run.mean().psnr;
    }
    row.best = best->mean();
    row.best.ms = best->mean_ms();
    row.best_dis = best->mean(true);
    row.fastest = fastest->mean();
    row.fastest.ms = fastest->mean_ms();
    row.fastest_dis = fastest->mean(true);
    row.render_left_ms = render_left;
    row.render_right_ms = render_right;
    row.disoccluded_fraction = dis_fraction;
    return row;
}

// The scene's CSV rows, summary row and report sections (all pixels, disoccluded ones).
Status add_scene(const std::string& scene_name, const std::string& name,
                 const std::vector<Run>& runs, std::size_t render_i, const Run& alternate,
                 double render_left, double render_right, double alternate_render,
                 double dis_fraction, const std::string& out_dir, CsvFile& csv,
                 std::vector<SceneSummary>& summaries, Report& report) {
    char text[512];
    ReportSection all{name}, dis_section{name + ", disoccluded pixels only"};
    for (const server::SceneInfo& info : server::builtin_scenes())
        if (scene_name == info.name) all.note = info.stresses;
    for (const Run& run : runs) {
        for (const Score& s : run.scores) {
            csv.error_row(name, run.method, run.setting, s.frame, s.all, s.ms);
            csv.error_row(name, run.method, run.setting + "+disoccluded", s.frame, s.disoccluded,
                          s.ms);
        }
        all.points.push_back(run.mean());
        dis_section.points.push_back(run.mean(true));
    }
    for (const Score& s : alternate.scores)
        csv.error_row(name, alternate.method, alternate.setting, s.frame, s.all, s.ms);
    all.points.push_back(alternate.mean());
    csv.flush();

    const Run *best = nullptr, *peer = nullptr;
    SceneSummary row = summarize(name, runs, render_left, render_right, dis_fraction, best, peer);
    row.alternate = alternate.mean();
    row.alternate.ms = alternate.mean_ms();
    row.alternate_render_ms = alternate_render;
    summaries.push_back(row);
    std::snprintf(
        text, sizeof text,
        " Mean disoccluded fraction %.2f%%; renderer: left eye %.2f ms, right eye %.2f ms; "
        "pair ratio (render + ours %s) / (two renders) = %.3f.",
        100.0 * dis_fraction, render_left, render_right, best->setting.c_str(),
        row.ratio(row.best));
    all.note += text;
    const std::string picture = name + "/worst_frame.png";
    REPRISE_TRY(worst_picture(*best, runs[render_i], peer, out_dir + "/" + picture));
    all.images.push_back({picture, "The lowest-PSNR frame of our best setting (" + best->setting +
                                       ") beside the rendered right eye and the best peer (" +
                                       (peer ? peer->method : std::string("-")) +
                                       "); below, the window where ours differs most, enlarged."});
    report.sections.push_back(std::move(all));
    report.sections.push_back(std::move(dis_section));
    return {};
}

// Sequence folders given by --in: the left eye in DIR/input (scripts/blender-scenes --stereo) or
// DIR/left (reprise render --stereo), the right eye in DIR/right.
fs::path left_eye_dir(const fs::path& dir) {
    return holds_exr(dir / "input") ? dir / "input" : dir / "left";
}
bool holds_eyes(const fs::path& dir) {
    return holds_exr(left_eye_dir(dir)) && holds_exr(dir / "right");
}

float eye_distance(const Camera& a, const Camera& b) {
    return glm::length(glm::vec3(glm::inverse(a.view)[3]) - glm::vec3(glm::inverse(b.view)[3]));
}

}  // namespace

Status bench_stereo(const BenchOptions& options) {
    int w = 0, h = 0;
    REPRISE_TRY(parse_size(options.size, w, h));
    std::vector<std::string> scenes = split_list(options.scenes);
    if (scenes.empty() && options.in.empty())
        for (const server::SceneInfo& s : server::builtin_scenes()) scenes.push_back(s.name);
    for (const std::string& sequence : sequence_folders(options.in, holds_eyes))
        scenes.push_back(sequence);
    const std::string out_dir = options.out.empty() ? "out/bench-stereo" : options.out;
    std::error_code ec;
    fs::create_directories(out_dir, ec);
    if (ec) return Status::error(out_dir + ": cannot create the folder: " + ec.message());
    const std::string csv_path = out_dir + "/stereo.csv";
    CsvFile csv;
    REPRISE_TRY(csv.open(csv_path, kErrorTimeColumns));

    std::unique_ptr<server::Renderer> renderer;
    REPRISE_TRY(server::Renderer::create(renderer));
    const stereo::StereoRig rig{.ipd = 0.064f};
    const int frames = std::min(options.frames, 5);
    const int repeat = std::max(options.repeat, 1);
    const double fps = 30.0;
    const bool full_hd = w == 1920 && h == 1080;

    const std::vector<OurSetting> settings = our_settings();

    Report report;
    describe(rig, w, h, frames, repeat, renderer->device(), report);
    char text[2048];
    stereo::StereoSynthesizer synthesizer, probe_synth;
    Frame left, right, made, probe, history;
    Image<glm::vec3> truth_d(w, h), test_d(w, h);
    Image<uint8_t> disoccluded(w, h), holes(w, h);
    Image<glm::vec4> remapped, copied;
    std::vector<SceneSummary> summaries;
    Status failure;
    for (const std::string& scene_name : scenes) {
        server::Scene scene;
        server::CameraPath path;
        const bool sequence = is_sequence(scene_name);
        const std::string dir = sequence ? scene_name.substr(std::strlen(kSequencePrefix)) : "";
        Sequence lefts, rights;
        int scene_frames = frames;
        if (sequence) {
            failure = open_sequence(left_eye_dir(dir).string(), lefts);
            if (failure.ok()) failure = open_sequence(dir + "/right", rights);
            if (!failure.ok()) break;
            // Frame i is scored with frame i - 1 of the right eye as the history.
            scene_frames =
                std::min<int>(frames, int(std::min(lefts.files.size(), rights.files.size())) - 1);
            if (scene_frames < 1) {
                failure = Status::error(dir +
                                        ": needs two frames of each eye (input/ or left/, "
                                        "and right/)");
                break;
            }
        } else {
            failure = server::load_scene(scene_name, scene, path);
            if (!failure.ok()) break;
        }
        const std::string name = fs::path(sequence ? dir : scene_name).filename().stem().string();
        fs::create_directories(out_dir + "/" + name, ec);
        std::vector<Run> runs;
        for (const OurSetting& s : settings) runs.push_back({kOurs, s.setting});
        const std::size_t splat_i = runs.size();
        runs.push_back({kSplatPeer, "nofill"});
        runs.push_back({kSplatPeer, "telea"});  // the same, holes by cv::inpaint Telea
        runs.push_back({kRemapPeer, "linear"});
        runs.push_back({kCopyPeer, "-"});
        const std::size_t render_i = runs.size();
        runs.push_back({kRender, "right eye"});
        double render_left = 0.0, render_right = 0.0, dis_fraction = 0.0;
        // Eye alternation over the same frames: frame i renders EyeAlternation::rendered_eye(i)
        // and makes the other; before frame 0 it keeps the right eye of the frame before.
        stereo::EyeAlternation alternation;
        Run alternate{kAlternate, "grid+pullpush"};
        double alternate_render = 0.0;
        Image<glm::vec3> other_truth_d(w, h);

        auto render_eye = [&](double t, stereo::Eye e, int times, Frame& out, double& ms) {
            return cli::render_eye(*renderer, scene, path, rig, w, h, t, e, times, out, ms);
        };
        // Frame i's eyes and the right eye of the frame before: rendered, or read (no render
        // time then).
        auto next_frames = [&](int i, double& left_ms, double& right_ms) -> Status {
            if (sequence) {
                left_ms = right_ms = NAN;
                REPRISE_TRY(read_frame(lefts, std::size_t(i) + 1, left));
                REPRISE_TRY(read_frame(rights, std::size_t(i) + 1, right));
                REPRISE_TRY(read_frame(rights, std::size_t(i), history));
                if (right.width() != left.width() || right.height() != left.height() ||
                    left.depth.width() != left.width() || left.depth.height() != left.height())
                    return Status::error(dir +
                                         ": the eyes differ in size or the left has no depth");
                return {};
            }
            const double t = (i + 10) / fps;
            double unused = 0.0;
            REPRISE_TRY(render_eye(t, stereo::Eye::Left, repeat, left, left_ms));
            REPRISE_TRY(render_eye(t, stereo::Eye::Right, repeat, right, right_ms));
            return render_eye(t - 1.0 / fps, stereo::Eye::Right, 1, history, unused);
        };

        if (!sequence) {  // warm-up (shader compilation, first upload of the scene): not timed
            double unused = 0.0;
            failure = render_eye(10 / fps, stereo::Eye::Left, 1, left, unused);
        }
        for (int i = 0; i < scene_frames && failure.ok(); ++i) {
            double left_ms = 0.0, right_ms = 0.0;
            failure = next_frames(i, left_ms, right_ms);
            if (!failure.ok()) break;
            const int fw = left.width(), fh = left.height();
            truth_d.resize(fw, fh), test_d.resize(fw, fh), disoccluded.resize(fw, fh);
            other_truth_d.resize(fw, fh), holes.resize(fw, fh);
            render_left += left_ms / scene_frames, render_right += right_ms / scene_frames;
            const Camera& target = right.camera;
            stereo::StereoRig eye_rig = rig;  // a sequence's eyes stand as far apart as they do
            if (sequence) eye_rig.ipd = eye_distance(left.camera, right.camera);

            probe_synth.synthesize(left, target, probe,
                                   {.warp = stereo::StereoWarp::Splat,
                                    .fill = stereo::StereoFill::None,
                                    .splat = {.footprint = 1},
                                    .widen_silhouettes = false});
            std::size_t dis = 0;
            for (std::size_t k = 0; k < disoccluded.pixel_count(); ++k)
                dis += disoccluded.data()[k] = !probe_synth.coverage().data[k];
            dis_fraction += double(dis) / double(disoccluded.pixel_count()) / scene_frames;
            to_display(right.color.view(), truth_d.view());

            auto record_display = [&](Run& run, double ms) {
                Score s{.frame = i, .ms = ms};
                s.all = image_error(truth_d.view(), test_d.view());
                s.disoccluded = dis ? image_error(truth_d.view(), test_d.view(), disoccluded.view())
                                    : ImageError{NAN, NAN, NAN};
                run.scores.push_back(s);
                to_rgb8(test_d.view(), run.shown[i]);
            };
            auto record = [&](Run& run, const Image<glm::vec4>& test, double ms) {
                to_display(test.view(), test_d.view());
                record_display(run, ms);
            };
            for (std::size_t k = 0; k < settings.size(); ++k) {
                const double ms = fastest_ms(repeat, [&] {
                    synthesizer.synthesize(left, target, made, settings[k].options,
                                           settings[k].history ? &history : nullptr);
                });
                record(runs[k], made.color, ms);
            }
            double ms = fastest_ms(repeat, [&] {
                synthesizer.synthesize(left, target, made,
                                       {.warp = stereo::StereoWarp::Splat,
                                        .fill = stereo::StereoFill::None,
                                        .splat = {.footprint = 1},
                                        .widen_silhouettes = false});
            });
            record(runs[splat_i], made.color, ms);
            for (std::size_t k = 0; k < holes.pixel_count(); ++k)
                holes.data()[k] = !synthesizer.coverage().data[k];
            ms += fastest_ms(repeat, [&] {
                to_display(made.color.view(), test_d.view());
                inpaint_telea(test_d.view(), holes.view());
            });
            record_display(runs[splat_i + 1], ms);
            ms = fastest_ms(repeat, [&] { remap_by_disparity(left, eye_rig, remapped); });
            record(runs[splat_i + 2], remapped, ms);
            ms = fastest_ms(repeat, [&] { copied = left.color; });
            record(runs[splat_i + 3], copied, ms);
            record(runs[render_i], right.color, right_ms);

            if (i == 0) alternation.next(history, stereo::Eye::Right, history.camera, made);
            const stereo::Eye eye = stereo::EyeAlternation::rendered_eye(i);
            const Frame& shown = eye == stereo::Eye::Left ? left : right;
            const Frame& other = eye == stereo::Eye::Left ? right : left;
            ms = fastest_ms(repeat, [&] { alternation.next(shown, eye, other.camera, made); });
            to_display(other.color.view(), other_truth_d.view());
            to_display(made.color.view(), test_d.view());
            alternate.scores.push_back({.frame = i,
                                        .all = image_error(other_truth_d.view(), test_d.view()),
                                        .disoccluded = {NAN, NAN, NAN},
                                        .ms = ms});
            alternate_render += (eye == stereo::Eye::Left ? left_ms : right_ms) / scene_frames;
            std::printf("[stereo] %s frame %d: render L %.1f ms, R %.1f ms, %.2f%% disoccluded\n",
                        name.c_str(), i, left_ms, right_ms,
                        100.0 * double(dis) / disoccluded.pixel_count());
            std::fflush(stdout);
        }
        if (!failure.ok()) break;

        failure = add_scene(scene_name, name, runs, render_i, alternate, render_left, render_right,
                            alternate_render, dis_fraction, out_dir, csv, summaries, report);
        if (!failure.ok()) break;
    }
    REPRISE_TRY(failure);

    const std::string table = summary_table(summaries, full_hd) +
                              "\neye alternation (Didyk et al. 2010): each frame renders one eye, "
                              "left on even frames, and makes the other with that eye's last "
                              "rendered frame as history; PSNR of the made eye (both eyes "
                              "taking turns) against the rendered one; grid+pp, +history: the "
                              "right eye always made from the left, without and with the "
                              "previous rendered right eye; ratio = (render of the one eye + "
                              "ms) / (render L + render R)\n" +
                              alternation_table(summaries);
    std::snprintf(
        text, sizeof text,
        "stereo, %dx%d (sequences: as read), %d frames per scene, ipd %.3f (sequences: their "
        "cameras'), fastest of %d runs, %d threads; PSNR dB (psnr_d: disoccluded pixels only); ms "
        "per synthesized eye; splat/telea/remap/"
        "copyL: peers' PSNR; render_ms: the renderer's right eye; dis%%: disoccluded "
        "pixels; ratio = (render L + ours) / (render L + render R); per scene our best "
        "setting by PSNR, "
        "then our fastest\n",
        w, h, frames, rig.ipd, repeat, thread_count());
    report.preformatted = std::string(text) + table;
    const std::string html_path = out_dir + "/index.html";
    REPRISE_TRY(write_html_report(html_path, report));
    std::printf("%s%s", text, table.c_str());
    std::printf("report: %s\nrows: %s\n", html_path.c_str(), csv_path.c_str());
    return {};
}

}  // namespace reprise::cli
