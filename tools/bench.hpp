#pragma once
// Benchmarks behind `reprise bench WHAT`. Each prints its timings and, for kernels, the ratio
// against a peer (OpenCV, ffmpeg) measured in the same run on the same input.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "reprise/core/status.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"

namespace reprise::cli {

struct BenchOptions {
    std::string scene = "pan";
    int frames = 10;  // repetitions / frames per measurement
    std::string sizes = "640x360,1920x1080";
    std::string dir;              // where files go (default: the temp folder)
    std::string backend = "cpu";  // bench paths: cpu, or gles for the GPU stages beside the CPU
    std::string out;              // report folder (bench fruc)
    // bench fruc
    std::string scenes;  // comma-separated; empty = every built-in scene
    int factor = 2;      // K
    std::string size = "640x360";
    bool quick = false;  // a few settings only
    bool exr = false;    // also write the rendered input and truth as EXR
    int repeat = 3;      // timed runs; each frame's fastest counts
    int aa = 4;          // render, fruc: anti-aliasing samples (render compares 1 with it)
    // bench codec
    std::string in;                        // a sequence folder, besides the scenes
    int threads = 2;                       // per codec
    std::string qps = "22,28,34,40";       // reprise's rate points
    std::string speed_size = "1920x1080";  // the speed ratios' size
    std::string speed_scene = "pan";
    int speed_frames = 10;  // 0 = no speed run
    // bench stream
    double stream_duration = 4.0;  // seconds per condition
    double display_rate = 120.0;
    std::string conditions;  // comma-separated condition names; empty = all (or --quick)
};

// A scene, its camera path and a renderer: what every benchmark that renders starts from.
struct BenchScene {
    server::Scene scene;
    server::CameraPath path;
    std::unique_ptr<server::Renderer> renderer;
};
Status open_bench_scene(const std::string& name, BenchScene& bench);

// Sequence folders given by --in stand among a bench's scenes as "in:DIR".
inline constexpr const char* kSequencePrefix = "in:";
bool is_sequence(const std::string& scene);
bool holds_exr(const std::filesystem::path& dir);
// Each comma-separated folder of `spec` that `holds` accepts, else the folders inside it that it
// accepts (natural order), else the folder itself (opening it then names what is missing); each
// as "in:DIR".
std::vector<std::string> sequence_folders(const std::string& spec,
                                          bool (*holds)(const std::filesystem::path&));

Status bench_reproject(const BenchOptions& options);  // reverse reprojection vs cv::remap
Status bench_grid(const BenchOptions& options);       // splat and adaptive grid warp
Status bench_fill(const BenchOptions& options);       // pull-push, Andreev vs cv::inpaint (Telea)
// Every (kernel, reference) pair of the warp kernel registry at every SIMD level, against the
// reference and cv::remap, after checking each level agrees: OUT/kernels.csv.
Status bench_kernels(const BenchOptions& options);
// Whole made frames (interpolation, extrapolation, the second eye) against cv::remap, one run.
Status bench_paths(const BenchOptions& options);
// The GPU backend's stages beside their CPU references on `frames` (consecutive, at least 3):
// upload, compute and download ms apart (bench paths --backend gles).
Status bench_gles_stages(const std::vector<Frame>& frames, const std::string& size);
// Upconversion error against run time, every setting and the peers (ffmpeg minterpolate,
// OpenCV DIS flow, Telea): OUT/fruc.csv, OUT/fruc_summary.csv, OUT/index.html.
Status bench_fruc(const BenchOptions& options);
// Synthesized second eye vs the rendered one, naive DIBR peers and the renderer's second-eye
// time, per built-in scene (--scenes, --size, --frames up to 5, --repeat): OUT/stereo.csv (with
// "+disoccluded" rows), OUT/index.html, OUT/SCENE/worst_frame.png and a summary on stdout.
Status bench_stereo(const BenchOptions& options);
// reprise's codec against x264, x265, SVT-AV1 (libavcodec) on the same frames: bits, PSNR, SSIM,
// FLIP, encode and decode ms per frame; BD-rates; depth against zstd -3 and RVL; speed ratios at
// 1080p; issue 8's targets as met / not met: OUT/codec.csv, bd_rate.csv, depth.csv, speed.csv,
// index.html.
Status bench_codec(const BenchOptions& options);
// Shading reuse in the heavy renderer (reprojection cache, refresh policies, adaptive reshading)
// per heavy scene (--scenes, default courtyard,stroll; --size, --frames, --quick): shading-pass
// speed-up against full shading in the same run, hit rate, pixels shaded, error against full
// shading every frame: OUT/reuse.csv, OUT/reuse_summary.csv, OUT/index.html.
Status bench_reuse(const BenchOptions& options);

// The remote-rendering loop on loopback under injected faults (loss, burst, jitter, delay, a
// bandwidth cap): latency, bitrate, displayed-frame error and freezes of reprise's extrapolating
// client beside frame repetition and an x264 video-only model: OUT/stream.csv,
// stream_summary.csv, index.html.
Status bench_stream(const BenchOptions& options);
// Spatio-temporal upsampling (Herzog 2010) of low-resolution jittered colour against the full
// render, beside cv::resize, a jitter-aware warpAffine and joint bilateral upsampling, per scene
// and factor (--factor 2|4, default both); ms per 1080p frame against cv::remap:
// OUT/upsample.csv, OUT/speed.csv, OUT/index.html, OUT/SCENE_1ofF.png.
Status bench_upsample(const BenchOptions& options);

}  // namespace reprise::cli
