// reprise stereo: the other eye of every frame of a rendered sequence.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include <glm/gtc/matrix_transform.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "input_range.hpp"
#include "outputs.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/core/memory_limit.hpp"
#include "reprise/core/nonfinite.hpp"
#include "reprise/gpu/context.hpp"
#include "reprise/stereo/rig.hpp"
#include "reprise/stereo/synthesize.hpp"

namespace reprise::cli {

namespace {

struct StereoJob {
    std::string in, out, rig = "parallel", eye = "left", warp = "grid", fill = "pullpush";
    std::string backend = "cpu";
    std::string silhouettes = "widen";
    std::string blend = "perceptual";
    double ipd = 0.064;
    double convergence = 10.0;
    double fov = 0.0;  // degrees, for inputs without a camera
    bool temporal = false;
    bool resume = false, overwrite_inputs = false;
    std::string range;  // --range A:B: frames A..B only
    std::string line;   // the options given, recorded for --resume
};

Status check(const StereoJob& j, stereo::StereoRig& rig, stereo::StereoOptions& options) {
    if (j.in.empty()) return Status::error("--in DIR is required");
    if (j.out.empty()) return Status::error("--out DIR is required");
    if (!(j.ipd > 0.0 && j.ipd <= 1e6))
        return Status::error("--ipd must be a positive distance (which eye is given: --eye)");
    if (!(j.convergence > 0.0 && j.convergence <= 1e30))
        return Status::error("--convergence must be a positive distance");
    if (!(j.fov >= 0.0 && j.fov < 180.0))
        return Status::error("--fov must be a vertical field of view in degrees, in (0, 180)");
    if (j.rig != "parallel" && j.rig != "offaxis")
        return Status::error("--rig: '" + j.rig + "' is not parallel or offaxis");
    if (j.eye != "left" && j.eye != "right")
        return Status::error("--eye: '" + j.eye + "' is not left or right");
    if (j.warp != "grid" && j.warp != "grid-bicubic" && j.warp != "grid-bilinear" &&
        j.warp != "splat")
        return Status::error("--warp: '" + j.warp +
                             "' is not grid, grid-bicubic, grid-bilinear or splat");
    if (j.fill != "pullpush" && j.fill != "andreev" && j.fill != "patch" && j.fill != "none")
        return Status::error("--fill: '" + j.fill + "' is not pullpush, andreev, patch or none");
    if (j.backend != "cpu" && j.backend != "gles")
        return Status::error("--backend: '" + j.backend + "' is not cpu or gles");
    if (j.silhouettes != "widen" && j.silhouettes != "keep")
        return Status::error("--silhouettes: '" + j.silhouettes + "' is not widen or keep");
    if (j.blend != "perceptual" && j.blend != "linear")
        return Status::error("--blend: '" + j.blend + "' is not perceptual or linear");
    if (j.backend == "gles" && (j.fill == "andreev" || j.fill == "patch"))
        return Status::error(
            "--backend gles: the GPU fills with --fill pullpush or none (Andreev's and the patch "
            "fill are not on the GPU yet)");
    rig = {.ipd = float(j.ipd),
           .convergence = float(j.convergence),
           .rig = j.rig == "offaxis" ? stereo::Rig::OffAxis : stereo::Rig::Parallel};
    options = {.warp = j.warp == "splat" ? stereo::StereoWarp::Splat : stereo::StereoWarp::Grid,
               .fill = j.fill == "andreev" ? stereo::StereoFill::Andreev
                       : j.fill == "patch" ? stereo::StereoFill::Patch
                       : j.fill == "none"  ? stereo::StereoFill::None
                                           : stereo::StereoFill::PullPush};
    if (j.warp == "grid-bicubic" || j.warp == "grid-bilinear")
        options.grid.bicubic = j.warp == "grid-bicubic";
    options.widen_silhouettes = j.silhouettes == "widen";
    options.perceptual = j.blend == "perceptual";
    return {};
}

Status run_stereo(const StereoJob& job, const stereo::StereoRig& rig,
                  const stereo::StereoOptions& options) {
    Sequence seq;
    REPRISE_TRY(open_sequence(job.in, seq));
    REPRISE_TRY(check_one_size(seq, "stereo"));
    const bool given_left = job.eye == "left";
    const OutputRules rules{.inputs = {job.in}, .overwrite_inputs = job.overwrite_inputs};
    InputRange range;
    REPRISE_TRY(parse_input_range(job.range, seq.files.size(), "frames", range));
    if (!range.all && job.resume)
        return Status::error("--range and --resume cannot be combined (run the range again)");
    const std::string line = range.all ? job.line : std::string();  // chunks share a folder
    OutputFolder rendered, made_eye;
    REPRISE_TRY(check_output("--out", job.out, true, rules));
    REPRISE_TRY(
        rendered.open(job.out + (given_left ? "/left" : "/right"), rules, line, job.resume));
    REPRISE_TRY(
        made_eye.open(job.out + (given_left ? "/right" : "/left"), rules, line, job.resume));
    // Resumed, or a range: the temporal fill reads the frame before the first one written.
    const int on_disk = std::min(rendered.frames_on_disk(), made_eye.frames_on_disk());
    const std::size_t begin = range.all ? std::size_t(on_disk) : range.first;
    const std::size_t end = range.all ? seq.files.size() : range.last + 1;
    const std::size_t first = begin - (job.temporal && begin > 0 ? 1 : 0);
    if (on_disk > 0)
        std::fprintf(stderr, "[stereo] resuming: %d frames on disk, restarting at input %zu\n",
                     on_disk, first);
    stereo::StereoSynthesizer synthesizer;
    std::unique_ptr<gpu::Context> gpu;
    if (job.backend == "gles") REPRISE_TRY(gpu::Context::create(gpu));
    Frame frame, previous, made;
    bool have_previous = false;
    double ms = 0.0;
    std::size_t holes = 0, stretched = 0, from_history = 0, history_moving = 0;
    NonfiniteRepair repair;  // the rendered eye is written too: repaired where it is read
    NonfiniteCounts nonfinite;
    for (std::size_t i = first; i < end; ++i) {
        const std::string& file = seq.files[i];
        REPRISE_TRY(read_frame(seq, i, frame));
        if (frame.depth.width() != frame.width() || frame.depth.height() != frame.height())
            return Status::error(file + ": needs a depth channel (Z) of the colour's size");
        // The synthesizer's scratch, the made eye and the history: measured 91 bytes a pixel,
        // before the widened source (12 more) and its encoded colour (StereoOptions::perceptual:
        // 16 more), counted.
        REPRISE_TRY(check_image_memory(frame.width(), frame.height(), 124, "stereo"));
        nonfinite += repair.repair(frame);
        // Disparity needs the focal length: from the file's camera, else from --fov.
        if (!has_projection(frame.camera)) {
            if (job.fov == 0.0)
                return Status::error(file +
                                     ": has no camera (Blender renders carry none); give "
                                     "--fov DEG, the camera's vertical field of view, or a "
                                     "cameras.json beside the frames");
            frame.camera.projection = glm::perspective(float(glm::radians(job.fov)),
                                                       float(frame.width()) / float(frame.height()),
                                                       frame.camera.near, frame.camera.far);
            frame.camera.prev_projection = frame.camera.projection;
        }
        const stereo::EyeCameras eyes = stereo::eye_cameras(
            frame.camera, rig, given_left ? stereo::Anchor::Left : stereo::Anchor::Right);
        // The file's camera is the rendered eye's as it was rendered; the rig only adds the other.
        const Camera& target = given_left ? eyes.right : eyes.left;
        if (i < begin) {  // the history of the first frame written, not written itself
            std::swap(previous, frame);
            have_previous = true;
            continue;
        }
        auto start = std::chrono::steady_clock::now();
        // Nothing of another shot fills this one's holes.
        const bool history = job.temporal && have_previous && frame.camera.cut != Cut::Yes;
        const GBufferView previous_view = previous.view();
        stereo::StereoStats stats;
        if (gpu)
            REPRISE_TRY(gpu->stereo_eye(frame, target, made, stats, options,
                                        history ? &previous_view : nullptr));
        else
            stats =
                synthesizer.synthesize(frame, target, made, options, history ? &previous : nullptr);
        made.fps = frame.fps;
        ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                  .count();
        holes += stats.holes;
        stretched += stats.stretched;
        from_history += stats.from_history;
        history_moving += stats.history_moving;
        REPRISE_TRY(rendered.write(int(i), frame));
        REPRISE_TRY(made_eye.write(int(i), made));
        if (job.temporal) {
            std::swap(previous, frame);
            have_previous = true;
        }
    }
    REPRISE_TRY(rendered.finish());
    REPRISE_TRY(made_eye.finish());
    const std::size_t made_count = end - begin;
    std::fprintf(stderr,
                 "[stereo] %zu frames, %.2f ms per eye, %zu holes, %zu stretched, %zu pixels from "
                 "history (%zu of its pixels left out as moving) -> %s\n",
                 made_count, made_count ? ms / double(made_count) : 0.0, holes, stretched,
                 from_history, history_moving, job.out.c_str());
    if (nonfinite.total() > 0)
        std::fprintf(stderr, "[stereo] input: %s\n", describe_nonfinite(nonfinite).c_str());
    return {};
}

}  // namespace

int command_stereo(int argc, char** argv) {
    StereoJob job;
    Args args("stereo",
              "The other eye of every frame of an EXR sequence (colour + depth + camera) by depth\n"
              "warping: OUT/left and OUT/right EXR sequences (the input eye copied as it is).\n"
              "Disparity d = f * ipd * (1/z - 1/convergence) px; near content shifts left in the "
              "right eye.");
    args.option("--in", &job.in, "input sequence folder (required)");
    args.option("--out", &job.out, "output folder (required)");
    args.option("--ipd", &job.ipd, "eye separation in scene units (default 0.064)");
    args.option("--convergence", &job.convergence,
                "zero-disparity distance, offaxis rig (default 10)");
    args.option("--fov", &job.fov,
                "vertical field of view in degrees, for inputs without a camera");
    args.option("--rig", &job.rig, "parallel|offaxis (default parallel)");
    args.option("--eye", &job.eye, "which eye the input is: left|right (default left)");
    args.option("--warp", &job.warp,
                "grid|splat (default grid; grid-bicubic, grid-bilinear pick its colour fetch, "
                "grid is bicubic)");
    args.option("--fill", &job.fill,
                "pullpush|andreev|patch|none (default pullpush; patch: frequency-selective "
                "reconstruction, slow)");
    args.option("--backend", &job.backend,
                "cpu|gles (default cpu); gles: OpenGL ES (compute shaders, and the rasteriser for "
                "the grid), with --fill pullpush or none");
    args.option("--silhouettes", &job.silhouettes,
                "widen|keep (default widen): pixels beside a nearer surface warp with it");
    args.option("--blend", &job.blend,
                "perceptual|linear (default perceptual): colour warped and filled as the square "
                "root of linear\nlight (close to the display's scale), or in linear light "
                "(--backend gles: always linear)");
    args.flag("--temporal", &job.temporal, "fill disocclusions from the previous frame first");
    args.option("--range", &job.range,
                "A:B: frames A..B only (--temporal reads frame A-1 first); ranges that meet "
                "give a whole\nrun's bytes (a farm's chunks)");
    args.flag("--resume", &job.resume,
              "continue an interrupted run of the same arguments from the frames in --out");
    args.flag("--overwrite-inputs", &job.overwrite_inputs,
              "allow --out where the inputs are (written after all are read)");
    Status parsed = args.parse(argc, argv);
    job.line = args.given_line({"--resume"});
    stereo::StereoRig rig;
    stereo::StereoOptions options;
    if (parsed.ok() && !args.help_requested()) {
        Status checked = check(job, rig, options);
        if (!checked.ok()) parsed = Status::error("stereo: " + checked.message());
    }
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    return report(args, parsed, run_stereo(job, rig, options));
}

}  // namespace reprise::cli
