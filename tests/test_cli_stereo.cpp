// `reprise render --stereo`, `reprise stereo` and `reprise export --stereo` end to end; the GPU
// backend of `reprise stereo` and `reprise fruc`.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "commands.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/core/metrics.hpp"
#include "support/cli.hpp"
#include "support/frames.hpp"

using namespace reprise;
namespace fs = std::filesystem;

namespace {

using test::display_psnr;
using test::run_command;

double psnr_of(const std::string& a_file, const std::string& b_file) {
    Frame a, b;
    EXPECT_TRUE(read_frame(a_file, a).ok());
    EXPECT_TRUE(read_frame(b_file, b).ok());
    return display_psnr(a.color, b.color);
}

}  // namespace

TEST(CliStereo, RenderBothEyesSynthesizeAndExport) {
    const fs::path dir =
        fs::temp_directory_path() / ("reprise_cli_stereo_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const std::string truth = (dir / "truth").string(), made = (dir / "made").string();
    ASSERT_EQ(run_command(cli::command_render, {"--scene", "pan", "--frames", "2", "--size",
                                                "160x90", "--stereo", "0.1", "--out", truth}),
              0);
    ASSERT_TRUE(fs::exists(frame_path(truth + "/left", 1)));
    ASSERT_TRUE(fs::exists(frame_path(truth + "/right", 1)));
    ASSERT_EQ(run_command(cli::command_stereo,
                          {"--in", truth + "/left", "--ipd", "0.1", "--temporal", "--out", made}),
              0);
    for (int i = 0; i < 2; ++i) {
        const std::string right = frame_path(truth + "/right", i);
        const double ours = psnr_of(right, frame_path(made + "/right", i));
        const double copy = psnr_of(right, frame_path(truth + "/left", i));
        EXPECT_GT(ours, 28.0);
        EXPECT_GT(ours, copy + 5.0);
    }
    // The grid's colour fetch: bicubic by default, bilinear on request (another eye, as good).
    const std::string bicubic = (dir / "bicubic").string(), bilinear = (dir / "bilinear").string();
    for (const auto& [fetch, out] :
         {std::pair{"grid-bicubic", bicubic}, {"grid-bilinear", bilinear}})
        ASSERT_EQ(run_command(cli::command_stereo, {"--in", truth + "/left", "--ipd", "0.1",
                                                    "--temporal", "--warp", fetch, "--out", out}),
                  0);
    const std::string right = frame_path(truth + "/right", 1);
    EXPECT_EQ(psnr_of(frame_path(made + "/right", 1), frame_path(bicubic + "/right", 1)), INFINITY);
    EXPECT_LT(psnr_of(frame_path(made + "/right", 1), frame_path(bilinear + "/right", 1)), 80.0);
    EXPECT_GT(psnr_of(right, frame_path(bilinear + "/right", 1)), 28.0);
    const std::string sbs = (dir / "sbs.png").string();
    ASSERT_EQ(run_command(cli::command_export, {made, "--stereo", "sbs", "--png", sbs}), 0);
    cv::Mat picture = cv::imread(sbs);
    EXPECT_EQ(picture.cols, 320);
    EXPECT_EQ(picture.rows, 90);
    const std::string tb = (dir / "tb").string() + "/";
    ASSERT_EQ(run_command(cli::command_export, {made, "--stereo", "tb", "--png", tb}), 0);
    EXPECT_EQ(cv::imread(tb + "frame_00001.png").rows, 180);
    fs::remove_all(dir);
}

TEST(CliStereo, BadArgumentsExitWithTwo) {
    EXPECT_EQ(run_command(cli::command_stereo, {"--in", "x", "--out", "y", "--rig", "diagonal"}),
              2);
    EXPECT_EQ(run_command(cli::command_stereo, {"--in", "x", "--out", "y", "--convergence", "-1"}),
              2);
    EXPECT_EQ(run_command(cli::command_stereo, {"--in", "x", "--out", "y", "--ipd", "abc"}), 2);
    EXPECT_EQ(run_command(cli::command_stereo, {"--in", "x", "--out", "y", "--warp", "grid-cubic"}),
              2);
    EXPECT_EQ(run_command(cli::command_stereo, {"--out", "y"}), 2);
    EXPECT_EQ(run_command(cli::command_export, {"x", "--stereo", "3d", "--png", "a.png"}), 2);
    // A folder that holds no sequence is bad data: exit 1.
    EXPECT_EQ(run_command(cli::command_stereo,
                          {"--in", "/nonexistent_reprise", "--out",
                           (fs::temp_directory_path() / "reprise_stereo_none").string()}),
              1);
}

// Blender renders carry no camera: without the focal length the eye would be wrong, so stereo
// refuses until --fov gives it, and then matches the run that had the camera.
TEST(CliStereo, InputWithoutACameraNeedsTheFieldOfView) {
    const fs::path dir =
        fs::temp_directory_path() / ("reprise_cli_stereo_fov_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const std::string truth = (dir / "truth").string(), bare = (dir / "bare").string();
    ASSERT_EQ(run_command(cli::command_render, {"--scene", "pan", "--frames", "1", "--size",
                                                "160x90", "--stereo", "0.1", "--out", truth}),
              0);
    Frame frame;
    ASSERT_TRUE(read_frame(frame_path(truth + "/left", 0), frame).ok());
    const double fov_degrees = 2.0 * std::atan(1.0 / frame.camera.projection[1][1]) * 180.0 / M_PI;
    frame.camera = Camera{};
    fs::create_directories(bare);
    ASSERT_TRUE(write_frame(frame_path(bare, 0), frame).ok());
    const test::Outcome refused = test::run_reprise(
        "stereo --in " + bare + " --ipd 0.1 --out " + (dir / "none").string(), 60);
    EXPECT_EQ(refused.status, 1) << refused.output;
    EXPECT_NE(refused.output.find("has no camera"), std::string::npos) << refused.output;
    EXPECT_NE(refused.output.find("--fov"), std::string::npos) << refused.output;
    EXPECT_FALSE(fs::exists(frame_path((dir / "none/right").string(), 0)));
    const std::string with_camera = (dir / "camera").string(), with_fov = (dir / "fov").string();
    ASSERT_EQ(run_command(cli::command_stereo,
                          {"--in", truth + "/left", "--ipd", "0.1", "--out", with_camera}),
              0);
    ASSERT_EQ(run_command(cli::command_stereo, {"--in", bare, "--ipd", "0.1", "--fov",
                                                std::to_string(fov_degrees), "--out", with_fov}),
              0);
    const std::string right = frame_path(truth + "/right", 0);
    const double camera_psnr = psnr_of(right, frame_path(with_camera + "/right", 0));
    const double fov_psnr = psnr_of(right, frame_path(with_fov + "/right", 0));
    EXPECT_GT(fov_psnr, 28.0);
    EXPECT_NEAR(fov_psnr, camera_psnr, 0.1);
    fs::remove_all(dir);
}

// --backend gles: the same eyes as the CPU's splat (bit-identical on llvmpipe; the bar is
// 50 dB) and grid, and the options the GPU lacks named.
TEST(CliStereo, TheGpuBackendMakesTheCpusEyes) {
    const fs::path dir =
        fs::temp_directory_path() / ("reprise_cli_stereo_gles_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const std::string truth = (dir / "truth").string();
    ASSERT_EQ(run_command(cli::command_render, {"--scene", "fence", "--frames", "2", "--size",
                                                "160x90", "--out", truth}),
              0);
    const std::string cpu = (dir / "cpu").string(), gles = (dir / "gles").string();
    // The GPU's eye works in linear light: the CPU's is made so to compare them.
    ASSERT_EQ(run_command(cli::command_stereo,
                          {"--in", truth, "--warp", "splat", "--blend", "linear", "--out", cpu}),
              0);
    ASSERT_EQ(run_command(cli::command_stereo,
                          {"--in", truth, "--warp", "splat", "--backend", "gles", "--out", gles}),
              0);
    for (int i = 0; i < 2; ++i)
        EXPECT_GE(psnr_of(frame_path(cpu + "/right", i), frame_path(gles + "/right", i)), 50.0);
    // The default eye (the grid): its cells grown and drawn on the GPU.
    const std::string grid_cpu = (dir / "grid_cpu").string(),
                      grid_gles = (dir / "grid_gles").string();
    ASSERT_EQ(
        run_command(cli::command_stereo, {"--in", truth, "--blend", "linear", "--out", grid_cpu}),
        0);
    ASSERT_EQ(
        run_command(cli::command_stereo, {"--in", truth, "--backend", "gles", "--out", grid_gles}),
        0);
    for (int i = 0; i < 2; ++i)
        EXPECT_GE(psnr_of(frame_path(grid_cpu + "/right", i), frame_path(grid_gles + "/right", i)),
                  50.0);
    const std::string grid_temporal = (dir / "grid_temporal").string(),
                      grid_gles_temporal = (dir / "grid_gles_temporal").string();
    ASSERT_EQ(run_command(cli::command_stereo, {"--in", truth, "--temporal", "--blend", "linear",
                                                "--out", grid_temporal}),
              0);
    ASSERT_EQ(run_command(cli::command_stereo, {"--in", truth, "--temporal", "--backend", "gles",
                                                "--out", grid_gles_temporal}),
              0);
    for (int i = 0; i < 2; ++i)
        EXPECT_GE(psnr_of(frame_path(grid_temporal + "/right", i),
                          frame_path(grid_gles_temporal + "/right", i)),
                  50.0);
    EXPECT_EQ(run_command(cli::command_stereo,
                          {"--in", truth, "--out", gles, "--backend", "gles", "--fill", "andreev"}),
              2);
    // --temporal: the previous frame fills the holes first, on the GPU as on the CPU.
    const std::string cpu_temporal = (dir / "cpu_temporal").string(),
                      gles_temporal = (dir / "gles_temporal").string();
    ASSERT_EQ(run_command(cli::command_stereo, {"--in", truth, "--warp", "splat", "--temporal",
                                                "--blend", "linear", "--out", cpu_temporal}),
              0);
    ASSERT_EQ(run_command(cli::command_stereo, {"--in", truth, "--warp", "splat", "--temporal",
                                                "--backend", "gles", "--out", gles_temporal}),
              0);
    for (int i = 0; i < 2; ++i)
        EXPECT_GE(psnr_of(frame_path(cpu_temporal + "/right", i),
                          frame_path(gles_temporal + "/right", i)),
                  50.0);
    EXPECT_EQ(run_command(cli::command_stereo, {"--in", truth, "--out", gles, "--backend", "cuda"}),
              2);
    fs::remove_all(dir);
}

// `reprise fruc --backend gles`: the CPU's frames (splat, grid, refinement), motion included,
// and the options the GPU lacks named before anything is written.
TEST(CliStereo, FrucOnTheGpuBackendMakesTheCpusSplatFrames) {
    const fs::path dir =
        fs::temp_directory_path() / ("reprise_cli_fruc_gles_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const std::string in = (dir / "in").string();
    ASSERT_EQ(run_command(cli::command_render, {"--scene", "crossing", "--frames", "3", "--size",
                                                "160x90", "--out", in}),
              0);
    const std::string cpu = (dir / "cpu").string(), gles = (dir / "gles").string();
    const std::vector<std::string> splat = {"--in",     in,    "--warp",        "splat",
                                            "--refine", "off", "--true-motion", "off"};
    auto with = [&](std::vector<std::string> extra) {
        std::vector<std::string> args = splat;
        args.insert(args.end(), extra.begin(), extra.end());
        return args;
    };
    // The GPU works in linear light: the CPU's frames are made so to compare them.
    ASSERT_EQ(run_command(cli::command_fruc, with({"--blend", "linear", "--out", cpu})), 0);
    ASSERT_EQ(run_command(cli::command_fruc, with({"--backend", "gles", "--out", gles})), 0);
    for (int i = 0; i < 5; ++i)
        EXPECT_GE(psnr_of(frame_path(cpu, i), frame_path(gles, i)), 50.0) << "frame " << i;
    Frame made, cpu_made;
    ASSERT_TRUE(read_frame(frame_path(gles, 1), made).ok());
    ASSERT_TRUE(read_frame(frame_path(cpu, 1), cpu_made).ok());
    ASSERT_FALSE(made.motion.empty());  // per output period, as the CPU's
    EXPECT_EQ(made.motion(80, 45), cpu_made.motion(80, 45));
    // The defaults (the grid, true motion, refinement): both sides' cells grown and drawn on the
    // GPU, refinement's survey and choices there, its flow on the CPU.
    const std::string cpu_grid_between = (dir / "cpu_grid_between").string(),
                      gles_grid_between = (dir / "gles_grid_between").string();
    ASSERT_EQ(run_command(cli::command_fruc,
                          {"--in", in, "--blend", "linear", "--out", cpu_grid_between}),
              0);
    ASSERT_EQ(run_command(cli::command_fruc,
                          {"--in", in, "--backend", "gles", "--out", gles_grid_between}),
              0);
    for (int i = 0; i < 5; ++i)
        EXPECT_GE(psnr_of(frame_path(cpu_grid_between, i), frame_path(gles_grid_between, i)), 50.0)
            << "the default in-between frame, frame " << i;
    // With true motion (the default) too.
    const std::string cpu_true = (dir / "cpu_true").string(),
                      gles_true = (dir / "gles_true").string();
    const std::vector<std::string> true_motion = {"--in", in, "--warp", "splat", "--refine", "off"};
    std::vector<std::string> run = true_motion;
    run.insert(run.end(), {"--blend", "linear", "--out", cpu_true});
    ASSERT_EQ(run_command(cli::command_fruc, run), 0);
    run = true_motion;
    run.insert(run.end(), {"--backend", "gles", "--out", gles_true});
    ASSERT_EQ(run_command(cli::command_fruc, run), 0);
    for (int i = 0; i < 5; ++i)
        EXPECT_GE(psnr_of(frame_path(cpu_true, i), frame_path(gles_true, i)), 50.0)
            << "true motion, frame " << i;
    // Extrapolated on the GPU: the CPU's frames, motion included.
    const std::vector<std::string> ahead = {"--in",        in,         "--warp", "splat", "--mode",
                                            "extrapolate", "--factor", "3"};
    const std::string cpu_ahead = (dir / "cpu_ahead").string(),
                      gles_ahead = (dir / "gles_ahead").string();
    std::vector<std::string> args = ahead;
    args.insert(args.end(), {"--blend", "linear", "--out", cpu_ahead});
    ASSERT_EQ(run_command(cli::command_fruc, args), 0);
    args = ahead;
    args.insert(args.end(), {"--backend", "gles", "--out", gles_ahead});
    ASSERT_EQ(run_command(cli::command_fruc, args), 0);
    for (int i = 0; i < 9; ++i)
        EXPECT_GE(psnr_of(frame_path(cpu_ahead, i), frame_path(gles_ahead, i)), 50.0)
            << "extrapolated frame " << i;
    ASSERT_TRUE(read_frame(frame_path(cpu_ahead, 2), cpu_made).ok());
    ASSERT_TRUE(read_frame(frame_path(gles_ahead, 2), made).ok());
    ASSERT_FALSE(made.motion.empty());
    EXPECT_EQ(made.motion(80, 45), cpu_made.motion(80, 45));
    // The default extrapolation, the grid: its cells grown and drawn on the GPU.
    const std::vector<std::string> grid_ahead = {"--in",        in,         "--mode",
                                                 "extrapolate", "--factor", "3"};
    const std::string cpu_grid = (dir / "cpu_grid").string(),
                      gles_grid = (dir / "gles_grid").string();
    args = grid_ahead;
    args.insert(args.end(), {"--blend", "linear", "--out", cpu_grid});
    ASSERT_EQ(run_command(cli::command_fruc, args), 0);
    args = grid_ahead;
    args.insert(args.end(), {"--backend", "gles", "--out", gles_grid});
    ASSERT_EQ(run_command(cli::command_fruc, args), 0);
    for (int i = 0; i < 9; ++i)
        EXPECT_GE(psnr_of(frame_path(cpu_grid, i), frame_path(gles_grid, i)), 50.0)
            << "extrapolated by the grid, frame " << i;
    const std::string refused = (dir / "refused").string();
    EXPECT_EQ(run_command(cli::command_fruc,
                          {"--in", in, "--backend", "gles", "--fill", "andreev", "--out", refused}),
              1);  // Andreev's fill: the CPU's alone
    EXPECT_EQ(run_command(cli::command_fruc, with({"--backend", "vulkan", "--out", refused})), 1);
    EXPECT_EQ(
        run_command(cli::command_fruc, {"--in", in, "--true-motion", "maybe", "--out", refused}),
        1);
    EXPECT_FALSE(fs::exists(refused));
    fs::remove_all(dir);
}
