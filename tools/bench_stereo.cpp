// reprise bench stereo: the synthesized eye against the rendered one, beside naive DIBR peers and
// the renderer's own time for the second eye, on every built-in scene.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "bench.hpp"
#include "args.hpp"
#include "reprise/core/metrics.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "reprise/stereo/rig.hpp"
#include "reprise/stereo/synthesize.hpp"

namespace reprise::cli {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

struct Row {
    std::string method;
    ImageError all, disoccluded;
    double ms = 0.0;
};

// Naive backward DIBR peer: right(x) = left(x + d(x)), d from the left eye's own depth at x.
void remap_by_disparity(const Frame& left, const stereo::StereoRig& rig, Image<glm::vec4>& out) {
    const int w = left.width(), h = left.height();
    cv::Mat map_x(h, w, CV_32F), map_y(h, w, CV_32F);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float z = left.depth(x, y);
            const float d = z > 0.0f ? stereo::disparity_px(rig, left.camera.projection, w, z) : 0.0f;
            map_x.at<float>(y, x) = float(x) + (std::isfinite(d) ? d : 0.0f);
            map_y.at<float>(y, x) = float(y);
        }
    out.resize(w, h);
    cv::Mat src(h, w, CV_32FC4, const_cast<glm::vec4*>(left.color.data()));
    cv::Mat dst(h, w, CV_32FC4, out.data());
    cv::remap(src, dst, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
}

}  // namespace

Status bench_stereo(const BenchOptions& options) {
    int w = 0, h = 0;
    REPRISE_TRY(parse_size(options.size, w, h));
    std::vector<std::string> scenes;
    if (options.scenes.empty()) {
        for (const server::SceneInfo& s : server::builtin_scenes()) scenes.push_back(s.name);
    } else {
        std::stringstream list(options.scenes);
        for (std::string s; std::getline(list, s, ',');) scenes.push_back(s);
    }
    const std::string out_dir = options.out.empty() ? "out/bench-stereo" : options.out;
    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    if (ec) return Status::error(out_dir + ": cannot create the folder: " + ec.message());
    const std::string csv_path = out_dir + "/stereo.csv";
    std::ofstream csv(csv_path);
    if (!csv) return Status::error(csv_path + ": cannot write");
    csv << "scene,method,setting,frame,psnr,ssim,flip,ms,psnr_disoccluded,ssim_disoccluded,"
           "flip_disoccluded,disoccluded_pixels\n";

    std::unique_ptr<server::Renderer> renderer;
    REPRISE_TRY(server::Renderer::create(renderer));
    const stereo::StereoRig rig{.ipd = 0.064f};
    const int frames = std::min(options.frames, 5);
    const double fps = 30.0;
    stereo::StereoSynthesizer synthesizer, disocclusion_probe;
    Frame left, right, made, probe;
    Image<glm::vec3> truth_d(w, h), test_d(w, h);
    Image<uint8_t> disoccluded(w, h);
    Image<glm::vec4> remapped;
    std::printf("%-9s %-14s %8s %8s %8s %9s %9s\n", "scene", "method", "psnr", "psnr_dis", "flip", "ms",
                "render_ms");
    for (const std::string& name : scenes) {
        server::Scene scene;
        server::CameraPath path;
        REPRISE_TRY(server::load_scene(name, scene, path));
        for (int i = 0; i < frames; ++i) {
            const double t = (i + 10) / fps;
            const server::Instant now = server::instant_on_path(path, scene, t, w, h);
            const server::Instant before = server::instant_on_path(path, scene, t - 1.0 / fps, w, h);
            Camera centre;
            centre.view = now.view;
            centre.projection = now.projection;
            centre.prev_view = before.view;
            centre.prev_projection = before.projection;
            const stereo::EyeCameras eyes = stereo::eye_cameras(centre, rig);
            double render_ms = 1e30;
            for (stereo::Eye e : {stereo::Eye::Left, stereo::Eye::Right})
                for (int r = 0; r < (e == stereo::Eye::Right ? options.repeat : 1); ++r) {
                    server::Instant a = now, b = before;
                    a.view = eyes[e].view;
                    a.projection = eyes[e].projection;
                    b.view = eyes[e].prev_view;
                    b.projection = eyes[e].prev_projection;
                    auto begin = Clock::now();
                    REPRISE_TRY(renderer->render(scene, a, b, {.width = w, .height = h},
                                                 e == stereo::Eye::Left ? left : right));
                    if (e == stereo::Eye::Right) render_ms = std::min(render_ms, ms_since(begin));
                }
            // Disoccluded: what no source pixel of the left eye lands on (nearest-pixel splat).
            disocclusion_probe.synthesize(left, eyes.right, probe,
                                          {.warp = stereo::StereoWarp::Splat,
                                           .fill = stereo::StereoFill::None,
                                           .splat = {.footprint = 1}});
            std::size_t dis = 0;
            for (std::size_t k = 0; k < disoccluded.pixel_count(); ++k)
                dis += disoccluded.data()[k] = !disocclusion_probe.coverage().data[k];
            to_display(right.color.view(), truth_d.view());
            auto measure = [&](const Image<glm::vec4>& test, Row& row) {
                to_display(test.view(), test_d.view());
                row.all = image_error(truth_d.view(), test_d.view());
                row.disoccluded = dis ? image_error(truth_d.view(), test_d.view(), disoccluded.view())
                                      : ImageError{};
            };
            std::vector<Row> rows;
            auto ours = [&](const char* method, stereo::StereoOptions o) {
                Row row{.method = method};
                row.ms = 1e30;
                for (int r = 0; r < options.repeat; ++r) {
                    auto begin = Clock::now();
                    synthesizer.synthesize(left, eyes.right, made, o);
                    row.ms = std::min(row.ms, ms_since(begin));
                }
                measure(made.color, row);
                rows.push_back(row);
            };
            ours("grid+pullpush", {});
            ours("grid+andreev", {.fill = stereo::StereoFill::Andreev});
            ours("splat+pullpush", {.warp = stereo::StereoWarp::Splat});
            ours("splat+none", {.warp = stereo::StereoWarp::Splat, .fill = stereo::StereoFill::None});
            {
                Row row{.method = "cv_remap"};
                row.ms = 1e30;
                for (int r = 0; r < options.repeat; ++r) {
                    auto begin = Clock::now();
                    remap_by_disparity(left, rig, remapped);
                    row.ms = std::min(row.ms, ms_since(begin));
                }
                measure(remapped, row);
                rows.push_back(row);
            }
            {
                Row row{.method = "render_right"};
                row.ms = render_ms;
                measure(right.color, row);
                rows.push_back(row);
                Row copy{.method = "copy_left"};
                measure(left.color, copy);
                rows.push_back(copy);
            }
            for (const Row& r : rows) {
                csv << name << ',' << r.method << ",ipd=" << rig.ipd << ',' << i << ',' << r.all.psnr << ','
                    << r.all.ssim << ',' << r.all.flip << ',' << r.ms << ',' << r.disoccluded.psnr << ','
                    << r.disoccluded.ssim << ',' << r.disoccluded.flip << ',' << dis << '\n';
                if (i == 0)
                    std::printf("%-9s %-14s %8.2f %8.2f %8.4f %9.2f %9.2f\n", name.c_str(), r.method.c_str(),
                                r.all.psnr, r.disoccluded.psnr, r.all.flip, r.ms, render_ms);
            }
        }
    }
    std::printf("[bench] %dx%d, %d frames per scene -> %s\n", w, h, frames, csv_path.c_str());
    return {};
}

}  // namespace reprise::cli
