// reprise bench render|exr — throughput of the renderer and of EXR frame I/O.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <vector>

#include "args.hpp"
#include "bench.hpp"
#include "commands.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"

namespace reprise::cli {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

struct BenchJob : BenchOptions {
    std::string what;
};

Status for_each_size(const std::string& sizes, const std::function<Status(int, int)>& run) {
    std::size_t start = 0;
    while (start <= sizes.size()) {
        std::size_t end = sizes.find(',', start);
        if (end == std::string::npos) end = sizes.size();
        int w = 0, h = 0;
        REPRISE_TRY(parse_size(sizes.substr(start, end - start), w, h));
        REPRISE_TRY(run(w, h));
        start = end + 1;
    }
    return {};
}

Status bench_render(const BenchJob& job) {
    BenchScene bench;
    REPRISE_TRY(open_bench_scene(job.scene, bench));
    auto& [scene, path, renderer] = bench;
    std::printf("renderer: %s, scene %s, %d frames per size\n", renderer->device().c_str(),
                job.scene.c_str(), job.frames);
    if (!server::aa_samples_valid(job.aa))
        return Status::error("bench render: --aa must be 1, 2, 4, 8 or 16");
    std::printf("%-11s %-18s %10s %10s %12s\n", "size", "anti-aliasing", "ms/frame", "frames/s",
                "x of aa 1");
    return for_each_size(job.sizes, [&](int w, int h) {
        Frame frame;
        double single_ms = 0.0;
        for (int aa : {1, job.aa}) {
            if (aa == 1 && single_ms > 0.0) break;
            const server::RenderSettings settings{.width = w, .height = h, .aa_samples = aa};
            REPRISE_TRY(renderer->render_frame(scene, path, 0, 30.0, settings, frame));  // warm-up
            auto start = Clock::now();
            for (int i = 1; i <= job.frames; ++i) {
                REPRISE_TRY(renderer->render_frame(scene, path, i, 30.0, settings, frame));
                std::fprintf(stderr, "\r[bench] %dx%d aa %d %d/%d", w, h, aa, i, job.frames);
            }
            const double ms = 1e3 * seconds_since(start) / job.frames;
            if (aa == 1) single_ms = ms;
            const std::string method = aa == 1 ? "off"
                                       : renderer->msaa_supported(aa)
                                           ? std::to_string(aa) + "x MSAA"
                                           : std::to_string(aa) + "x SSAA";
            std::fprintf(stderr, "\r%40s\r", "");
            std::printf("%-11s %-18s %10.1f %10.2f %12.2f\n",
                        (std::to_string(w) + "x" + std::to_string(h)).c_str(), method.c_str(), ms,
                        1e3 / ms, ms / single_ms);
        }
        return Status{};
    });
}

// EXR write and read of full G-buffer frames, against writing and reading the same bytes raw
// (the floor any file format pays), measured in the same run.
Status bench_exr(const BenchJob& job) {
    BenchScene bench;
    REPRISE_TRY(open_bench_scene(job.scene, bench));
    auto& [scene, path, renderer] = bench;
    std::string dir = job.dir.empty()
                          ? (std::filesystem::temp_directory_path() / "reprise-bench-exr").string()
                          : job.dir;
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) return Status::error(dir + ": " + ec.message());
    std::printf("EXR frames (R,G,B,A,Z,motion.x,motion.y,N.X,N.Y,N.Z,id; 32-bit, zip) in %s\n",
                dir.c_str());
    std::printf("%-11s %9s %9s %9s %9s %11s %11s\n", "size", "write ms", "read ms", "MB/frame",
                "file MB", "write/raw", "read/raw");
    return for_each_size(job.sizes, [&](int w, int h) {
        Frame frame, back;
        REPRISE_TRY(renderer->render_frame(scene, path, 0, 30.0, {.width = w, .height = h}, frame));
        const double bytes = double(w) * h * 11 * 4;
        std::vector<char> raw(static_cast<std::size_t>(bytes));
        std::string raw_path = dir + "/raw.bin";
        double write_s = 0, read_s = 0, raw_write_s = 0, raw_read_s = 0;
        for (int i = 0; i < job.frames; ++i) {
            std::string file = frame_path(dir, i);
            auto t = Clock::now();
            REPRISE_TRY(write_frame(file, frame));
            write_s += seconds_since(t);
            t = Clock::now();
            REPRISE_TRY(read_frame(file, back));
            read_s += seconds_since(t);
            t = Clock::now();
            std::ofstream(raw_path, std::ios::binary)
                .write(raw.data(), std::streamsize(raw.size()));
            raw_write_s += seconds_since(t);
            t = Clock::now();
            std::ifstream(raw_path, std::ios::binary).read(raw.data(), std::streamsize(raw.size()));
            raw_read_s += seconds_since(t);
            std::fprintf(stderr, "\r[bench] %dx%d %d/%d", w, h, i + 1, job.frames);
        }
        std::fprintf(stderr, "\r%40s\r", "");
        double file_mb = double(std::filesystem::file_size(frame_path(dir, 0))) / 1e6;
        std::printf("%-11s %9.1f %9.1f %9.1f %9.1f %10.1fx %10.1fx\n",
                    (std::to_string(w) + "x" + std::to_string(h)).c_str(),
                    1e3 * write_s / job.frames, 1e3 * read_s / job.frames, bytes / 1e6, file_mb,
                    write_s / raw_write_s, read_s / raw_read_s);
        for (int i = 0; i < job.frames; ++i) std::filesystem::remove(frame_path(dir, i), ec);
        std::filesystem::remove(raw_path, ec);
        return Status{};
    });
}

}  // namespace

int command_bench(int argc, char** argv) {
    BenchJob job;
    Args args(
        "bench",
        "Benchmarks. render: renderer frames per second; exr: frame write/read time against "
        "raw file I/O\nof the same bytes, measured in the same run. fruc: frame-rate upconversion "
        "error against run time\nfor every setting beside ffmpeg minterpolate and OpenCV DIS flow "
        "(CSV + HTML report in --out).\nstereo: the synthesized second eye against the rendered "
        "one, naive DIBR peers and the "
        "renderer's\nsecond-eye time (CSV + HTML report in --out). paths: whole made frames at "
        "display "
        "rate against cv::remap.\nkernels: each SIMD kernel at every level the CPU runs against "
        "its scalar reference and cv::remap (CSV in --out).\nreuse: shading reuse in the heavy "
        "renderer against full shading in the same run (speed-up, hit rate,\npixels shaded, error; "
        "CSV + HTML report in --out).\ncodec: reprise's codec beside x264, x265 and "
        "SVT-AV1\n(bits, PSNR/SSIM/FLIP, ms, BD-rates, depth coders, 1080p speed; CSV + HTML "
        "report in --out).\nupsample: Herzog spatio-temporal upsampling of 1/2 or 1/4 of the "
        "pixels against the full render,\nbeside cv::resize, warpAffine and joint bilateral peers; "
        "ms per 1080p frame against cv::remap (CSV + HTML).\nstream: the remote-rendering loop "
        "under injected faults (latency, bitrate, displayed error; --quick: 3 conditions).");
    args.positional("WHAT", &job.what,
                    "render | exr | reproject | grid | fill | paths | kernels | fruc | stereo | "
                    "codec | reuse | upsample | stream");
    args.option("--scene", &job.scene, "scene to render (default pan)");
    args.option("--frames", &job.frames,
                "frames per size (default 10); fruc: input frames (default 20); stereo: frames per "
                "scene (at most 5); upsample: frames per scene (default 12)");
    args.option("--sizes", &job.sizes, "comma-separated WxH list (default 640x360,1920x1080)");
    args.option("--backend", &job.backend,
                "paths: cpu (default), or gles for the GPU backend's stages beside the CPU's "
                "(OpenGL ES 3.1; upload, compute, download apart)");
    args.option("--dir", &job.dir, "exr: folder for the files (default: the temp folder)");
    args.option(
        "--out", &job.out,
        "fruc, stereo, codec, kernels, reuse, upsample: report folder (default out/bench-WHAT)");
    args.option(
        "--scenes", &job.scenes,
        "fruc, stereo, codec, reuse, upsample: comma-separated scenes or glTF files (default: "
        "every built-in scene; fruc adds the held-out glTF models, also named by held-out)");
    args.option("--factor", &job.factor,
                "fruc: K, output frames per input frame (default 2); upsample: 2 or 4 pixels per "
                "sample (default both)");
    args.option("--size", &job.size,
                "fruc, stereo, upsample: WxH (default 640x360); codec: default 1280x720");
    args.flag("--quick", &job.quick,
              "fruc: a few settings only (grid+pullpush, reverse+pullpush, splat+none, ...)");
    args.option("--aa", &job.aa,
                "render, fruc: anti-aliasing samples 1 (off), 2, 4, 8, 16 (default 4; render "
                "also times 1); stream: the server's and the video peers' sources' (default 1, "
                "the truth has 4)");
    args.option("--repeat", &job.repeat,
                "fruc, stereo, upsample: timed runs, each frame's fastest counts; codec: "
                "alternating rounds of the speed run, each codec's fastest counts (default 3)");
    args.option(
        "--in", &job.in,
        "codec: also a sequence folder (EXR frames, up to --frames); fruc: comma-separated "
        "sequence folders (input/ at 30 Hz, truth/ at 30 K Hz, as --exr writes them) or "
        "folders of them (scripts/blender-scenes), held out; stereo: folders of the two eyes "
        "(input/ or left/, and right/: scripts/blender-scenes --stereo IPD, reprise "
        "render --stereo) or folders of them; alone unless --scenes is given too");
    args.option("--threads", &job.threads, "codec: threads per codec (default 2)");
    args.option("--qps", &job.qps,
                "codec: reprise's qp rate points (default 22,28,34,40); stream: the server's qp "
                "(one, default 28)");
    args.option("--speed-size", &job.speed_size,
                "codec: size of the speed run (default 1920x1080)");
    args.option("--speed-scene", &job.speed_scene, "codec: scene of the speed run (default pan)");
    args.option("--speed-frames", &job.speed_frames,
                "codec, upsample: frames of the speed run (default 10; upsample 6; 0 = none)");
    args.option("--duration", &job.stream_duration, "stream: seconds per condition (default 4)");
    args.option("--display-rate", &job.display_rate,
                "stream: display frames per second (default 120)");
    args.option("--conditions", &job.conditions,
                "stream: comma-separated conditions (clean, loss1%, loss5%, burst, jitter20ms, "
                "rtt50ms, rtt100ms, rtt100ms+loss1%, cap1500kbps)");
    args.flag("--exr", &job.exr,
              "fruc: also write the rendered input and truth as EXR under OUT/SCENE/");
    Status parsed = args.parse(argc, argv);
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    if (job.what == "fruc" && !args.given("--frames")) job.frames = 20;  // reaches the cut at 0.5 s
    if (job.what == "codec" && !args.given("--frames")) job.frames = 30;
    if (job.what == "codec" && !args.given("--size")) job.size = "1280x720";
    if (job.what == "reuse" && !args.given("--frames")) job.frames = 24;
    if (job.what == "reuse" && !args.given("--size")) job.size = "256x144";
    if (job.what == "stream" && !args.given("--size")) job.size = "256x144";
    if (job.what == "stream" && !args.given("--qps")) job.qps = "28";
    if (job.what == "stream" && !args.given("--aa")) job.aa = 1;  // 640x360 at 4: 209 ms a frame
    if (job.what == "upsample" && !args.given("--frames")) job.frames = 12;
    if (job.what == "upsample" && !args.given("--factor")) job.factor = 0;  // both 4 and 2
    if (job.what == "upsample" && !args.given("--speed-frames")) job.speed_frames = 6;
    Status result;
    if (job.frames < 1 || job.frames > 100000)
        result = Status::error("bench: --frames must be in 1..100000");
    else if (job.what == "render")
        result = bench_render(job);
    else if (job.what == "exr")
        result = bench_exr(job);
    else if (job.what == "reproject")
        result = bench_reproject(job);
    else if (job.what == "grid")
        result = bench_grid(job);
    else if (job.what == "fill")
        result = bench_fill(job);
    else if (job.what == "paths")
        result = bench_paths(job);
    else if (job.what == "kernels")
        result = bench_kernels(job);
    else if (job.what == "fruc")
        result = bench_fruc(job);
    else if (job.what == "stereo")
        result = bench_stereo(job);
    else if (job.what == "codec")
        result = bench_codec(job);
    else if (job.what == "reuse")
        result = bench_reuse(job);
    else if (job.what == "upsample")
        result = bench_upsample(job);
    else if (job.what == "stream")
        result = bench_stream(job);
    else
        result = Status::error("bench: unknown benchmark '" + job.what +
                               "' (render, exr, reproject, grid, fill, paths, kernels, fruc, "
                               "stereo, codec, reuse, upsample, stream)");
    return report(args, parsed, result);
}

}  // namespace reprise::cli
