// `reprise render --lowres`, `reprise upsample` and `reprise bench upsample` end to end.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

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

fs::path scratch(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() /
                         ("reprise_cli_upsample_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    return dir;
}

}  // namespace

TEST(CliUpsample, RenderLowresThenUpsample) {
    const fs::path dir = scratch("run");
    const std::string rendered = (dir / "in").string(), made = (dir / "out").string();
    ASSERT_EQ(run_command(cli::command_render, {"--scene", "pan", "--frames", "6", "--size",
                                                "128x72", "--lowres", "4", "--out", rendered}),
              0);
    Frame full, low;
    ASSERT_TRUE(read_frame(frame_path(rendered, 5), full).ok());
    ASSERT_TRUE(read_frame(frame_path(rendered + "/lowres", 5), low).ok());
    EXPECT_EQ(full.width(), 128);
    EXPECT_EQ(low.width(), 64);
    EXPECT_EQ(low.height(), 36);
    EXPECT_EQ(full.camera.jitter, glm::vec2(0.0f));
    EXPECT_EQ(low.camera.jitter, glm::vec2(0.25f, 0.25f));  // frame 5: (+0.5, +0.5) full pixels
    ASSERT_EQ(run_command(cli::command_upsample, {"--in", rendered, "--out", made}), 0);
    Frame out;
    ASSERT_TRUE(read_frame(frame_path(made, 5), out).ok());
    ASSERT_EQ(out.width(), 128);
    EXPECT_FALSE(out.depth.empty());  // the G-buffer travels with the upsampled colour
    EXPECT_GT(display_psnr(full.color, out.color), 30.0);
    // --backend gles: the CPU's frames (the bar, 50 dB; identical on llvmpipe).
    const std::string on_gpu = (dir / "gles").string();
    ASSERT_EQ(run_command(cli::command_upsample,
                          {"--in", rendered, "--out", on_gpu, "--backend", "gles"}),
              0);
    for (int i = 0; i < 6; ++i) {
        Frame cpu, gpu;
        ASSERT_TRUE(read_frame(frame_path(made, i), cpu).ok());
        ASSERT_TRUE(read_frame(frame_path(on_gpu, i), gpu).ok());
        EXPECT_GE(display_psnr(cpu.color, gpu.color), 50.0) << "frame " << i;
    }
    EXPECT_NE(
        run_command(cli::command_upsample,
                    {"--in", rendered, "--out", (dir / "refused").string(), "--backend", "metal"}),
        0);
    EXPECT_FALSE(fs::exists(dir / "refused"));
    fs::remove_all(dir);
}

TEST(CliUpsample, BadArguments) {
    const fs::path dir = scratch("bad");
    EXPECT_NE(
        run_command(cli::command_render, {"--scene", "pan", "--frames", "1", "--size", "32x18",
                                          "--lowres", "3", "--out", (dir / "a").string()}),
        0);
    EXPECT_NE(run_command(cli::command_upsample,
                          {"--in", (dir / "missing").string(), "--out", (dir / "b").string()}),
              0);
    // A full-resolution sequence without its low-resolution colour.
    ASSERT_EQ(run_command(cli::command_render, {"--scene", "pan", "--frames", "1", "--size",
                                                "32x18", "--out", (dir / "c").string()}),
              0);
    EXPECT_NE(run_command(cli::command_upsample,
                          {"--in", (dir / "c").string(), "--out", (dir / "d").string()}),
              0);
    // Low colour larger than the full frame.
    EXPECT_NE(run_command(cli::command_upsample,
                          {"--in", (dir / "c").string(), "--low", (dir / "c").string(), "--out",
                           (dir / "d").string(), "--history-weight", "2"}),
              0);
    fs::remove_all(dir);
}

TEST(CliUpsample, BenchWritesItsReport) {
    const fs::path dir = scratch("bench");
    ASSERT_EQ(run_command(cli::command_bench,
                          {"upsample", "--scenes", "pan", "--size", "64x36", "--frames", "3",
                           "--factor", "4", "--repeat", "1", "--speed-size", "64x36",
                           "--speed-frames", "2", "--out", dir.string()}),
              0);
    const std::string csv = test::read_text(dir / "upsample.csv");
    EXPECT_NE(csv.find("pan,herzog,steered,2,"), std::string::npos);
    EXPECT_NE(csv.find("cv::resize,bilinear"), std::string::npos);
    EXPECT_NE(test::read_text(dir / "speed.csv").find("cv::remap,peer"), std::string::npos);
    EXPECT_TRUE(fs::exists(dir / "index.html"));
    fs::remove_all(dir);
}
