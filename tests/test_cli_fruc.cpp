// `reprise fruc` on input that lacks what rendered frames carry: colour only (plain renders,
// video) is interpolated with optical flow, and the command says so.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "commands.hpp"
#include "reprise/core/exr.hpp"
#include "support/cli.hpp"
#include "support/frames.hpp"

using namespace reprise;
namespace fs = std::filesystem;

TEST(CliFruc, ColorOnlyInputIsInterpolatedWithOpticalFlow) {
    const fs::path dir =
        fs::temp_directory_path() / ("reprise_cli_fruc_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const std::string rendered = (dir / "rendered").string(), truth = (dir / "truth").string();
    const std::string bare = (dir / "bare").string(), made = (dir / "made").string();
    ASSERT_EQ(
        test::run_command(cli::command_render, {"--scene", "pan", "--frames", "3", "--fps", "30",
                                                "--size", "192x108", "--out", rendered}),
        0);
    ASSERT_EQ(test::run_command(cli::command_render, {"--scene", "pan", "--frames", "5", "--fps",
                                                      "60", "--size", "192x108", "--out", truth}),
              0);
    fs::create_directories(bare);
    std::vector<Frame> input(3);
    for (int i = 0; i < 3; ++i) {
        ASSERT_TRUE(read_frame(frame_path(rendered, i), input[i]).ok());
        Frame color_only;
        color_only.color = input[i].color;
        color_only.fps = input[i].fps;
        ASSERT_TRUE(write_frame(frame_path(bare, i), color_only).ok());
    }
    const test::Outcome r =
        test::run_reprise("fruc --in " + bare + " --factor 2 --out " + made, 120);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("no motion channels"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("optical flow"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("no depth channel"), std::string::npos) << r.output;
    for (int k : {1, 3}) {
        Frame ours, expected;
        ASSERT_TRUE(read_frame(frame_path(made, k), ours).ok());
        ASSERT_TRUE(read_frame(frame_path(truth, k), expected).ok());
        const double psnr = test::display_psnr(expected.color, ours.color);
        const double repeat = test::display_psnr(expected.color, input[k / 2].color);
        std::printf("[fruc] colour only, frame %d: %.2f dB (repeating: %.2f dB)\n", k, psnr,
                    repeat);
        // Measured: 45.30 / 36.56 and 44.81 / 36.70 dB (each pair's flow from scratch).
        EXPECT_GT(psnr, 36.5) << k;
        EXPECT_GT(psnr, repeat + 1.5) << k;
    }
    // Motion estimated per pair from scratch: ranges of pairs give the whole run's bytes too.
    const std::string parts = (dir / "parts").string();
    for (const std::string range : {"0:0", "1:1"})
        ASSERT_EQ(test::run_reprise(
                      "fruc --in " + bare + " --factor 2 --range " + range + " --out " + parts, 120)
                      .status,
                  0);
    EXPECT_EQ(test::differences(test::frames(parts), test::frames(made)), "");
    fs::remove_all(dir);
}

namespace {

using test::differences;
using test::frames;
using test::q;

std::string scratch(const std::string& name) {
    return test::fresh_directory(fs::temp_directory_path() /
                                 ("reprise_cli_range_" + name + "_" + std::to_string(::getpid())))
        .string();
}

// 8 frames of the `cut` scene at 12 Hz: the camera cuts between inputs 5 and 6.
std::string render_cut(const std::string& dir) {
    const std::string in = dir + "/in";
    const test::Outcome r = test::run_reprise(
        "render --scene cut --frames 8 --fps 12 --size 32x24 --aa 1 --out " + q(in), 60);
    EXPECT_EQ(r.status, 0) << r.output;
    return in;
}

}  // namespace

// A farm's chunks: ranges of input pairs that meet write, together, the bytes of one whole run
// (cut detection, refinement, automatic choices and frame numbers included), each frame once.
TEST(CliFruc, RangesThatMeetWriteTheWholeRunsBytes) {
    const std::string dir = scratch("fruc"), in = render_cut(dir);
    for (const std::string options :
         {"--factor 3 --refine on", "--factor 2 --mode extrapolate --warp auto --fill auto"}) {
        const std::string fruc = "fruc --in " + q(in) + " " + options;
        const std::string whole_dir = test::fresh_directory(dir + "/whole").string();
        const test::Outcome whole = test::run_reprise(fruc + " --out " + q(whole_dir), 60);
        ASSERT_EQ(whole.status, 0) << whole.output;
        EXPECT_NE(whole.output.find(" 1 cuts"), std::string::npos) << whole.output;
        const std::string parts = dir + "/parts";
        test::fresh_directory(parts);
        std::size_t written = 0;
        for (const std::string range : {"0:2", "3:4", "5:5", "6:6"}) {
            const std::string part = parts + "/" + range;
            const test::Outcome r =
                test::run_reprise(fruc + " --range " + range + " --out " + q(part), 60);
            ASSERT_EQ(r.status, 0) << r.output;
            for (const auto& [name, bytes] : frames(part)) {
                fs::rename(fs::path(part) / name, fs::path(parts) / name);
                ++written;
            }
        }
        const std::size_t expected =
            options.find("extrapolate") != std::string::npos ? 8 * 2 : 7 * 3 + 1;
        EXPECT_EQ(frames(whole_dir).size(), expected) << options;
        EXPECT_EQ(written, expected) << options << ": a frame written by two ranges, or none";
        EXPECT_EQ(differences(frames(parts), frames(whole_dir)), "") << options;
    }
    fs::remove_all(dir);
}

// The temporal stereo fill reads the frame before: a range starts one frame early (read, not
// written), and without that frame its first frame would differ.
TEST(CliFruc, StereoRangesReadTheFrameBefore) {
    const std::string dir = scratch("stereo"), in = render_cut(dir);
    const std::string stereo = "stereo --temporal --ipd 0.3";
    ASSERT_EQ(
        test::run_reprise(stereo + " --in " + q(in) + " --out " + q(dir + "/whole"), 60).status, 0);
    for (const std::string range : {"0:2", "3:7"}) {
        const test::Outcome r = test::run_reprise(
            stereo + " --in " + q(in) + " --range " + range + " --out " + q(dir + "/parts"), 60);
        ASSERT_EQ(r.status, 0) << r.output;
    }
    EXPECT_EQ(frames(dir + "/parts").size(), 16u);
    EXPECT_EQ(differences(frames(dir + "/parts"), frames(dir + "/whole")), "");
    // The same frames 3..7 as a sequence of their own: frame 3 has no history.
    const std::string alone = dir + "/alone";
    fs::create_directories(alone);
    for (int i = 3; i < 8; ++i) fs::copy_file(frame_path(in, i), frame_path(alone, i));
    ASSERT_EQ(
        test::run_reprise(stereo + " --in " + q(alone) + " --out " + q(dir + "/cold"), 60).status,
        0);
    const auto cold = frames(dir + "/cold"), whole = frames(dir + "/whole");
    EXPECT_NE(cold.at("right/frame_00000.exr"), whole.at("right/frame_00003.exr"));
    fs::remove_all(dir);
}

TEST(CliFruc, BadRangesAreRefusedNamingTheRange) {
    const std::string dir = scratch("bad"), in = render_cut(dir);
    for (const std::string range : {"3:1", "0:7", "2:9", "a:b", "3", "-1:2", "1:2x", ":"}) {
        const test::Outcome r = test::run_reprise(
            "fruc --in " + q(in) + " --range " + range + " --out " + q(dir + "/out"), 60);
        EXPECT_NE(r.status, 0) << range;
        EXPECT_NE(r.output.find("--range"), std::string::npos) << range << ": " << r.output;
    }
    const test::Outcome r =
        test::run_reprise("stereo --in " + q(in) + " --range 0:8 --out " + q(dir + "/out"), 60);
    EXPECT_NE(r.output.find("the sequence has 8 frames"), std::string::npos) << r.output;
    const test::Outcome resumed = test::run_reprise(
        "fruc --in " + q(in) + " --range 0:1 --resume --out " + q(dir + "/out"), 60);
    EXPECT_NE(resumed.output.find("cannot be combined"), std::string::npos) << resumed.output;
    fs::remove_all(dir);
}

// `--blend linear` blends in linear light in both commands: other frames; a value that is
// neither is refused before anything is written.
TEST(CliFruc, ColourIsBlendedOnTheDisplaysScaleUnlessLinear) {
    const std::string dir = scratch("blend"), in = render_cut(dir);
    for (const std::string command : {"fruc", "stereo"}) {
        const std::string base = command + " --in " + q(in) + " --range 1:2 --out ";
        const test::Outcome perceptual = test::run_reprise(base + q(dir + "/perceptual"), 60);
        const test::Outcome linear =
            test::run_reprise(base + q(dir + "/linear") + " --blend linear", 60);
        ASSERT_EQ(perceptual.status, 0) << perceptual.output;
        ASSERT_EQ(linear.status, 0) << linear.output;
        EXPECT_NE(differences(frames(dir + "/perceptual"), frames(dir + "/linear")), "") << command;
        const test::Outcome bad = test::run_reprise(base + q(dir + "/bad") + " --blend gamma", 60);
        EXPECT_NE(bad.status, 0) << bad.output;
        EXPECT_NE(bad.output.find("--blend"), std::string::npos) << bad.output;
        EXPECT_NE(bad.output.find("'gamma'"), std::string::npos) << bad.output;
        EXPECT_FALSE(fs::exists(dir + "/bad")) << command;
        fs::remove_all(dir + "/perceptual");
        fs::remove_all(dir + "/linear");
    }
    fs::remove_all(dir);
}

// `--silhouettes keep` turns the widening off in both commands: other frames, a count of zero;
// a value that is neither is refused before anything is written.
TEST(CliFruc, SilhouettesAreWidenedUnlessKept) {
    const std::string dir = scratch("silhouettes"), in = render_cut(dir);
    for (const std::string command : {"fruc", "stereo"}) {
        const std::string base = command + " --in " + q(in) + " --range 1:2 --out ";
        const test::Outcome widened = test::run_reprise(base + q(dir + "/widen"), 60);
        const test::Outcome kept =
            test::run_reprise(base + q(dir + "/keep") + " --silhouettes keep", 60);
        ASSERT_EQ(widened.status, 0) << widened.output;
        ASSERT_EQ(kept.status, 0) << kept.output;
        EXPECT_NE(differences(frames(dir + "/widen"), frames(dir + "/keep")), "") << command;
        if (command == "fruc") {
            EXPECT_EQ(widened.output.find(" 0 input pixels with a nearer"), std::string::npos)
                << widened.output;
            EXPECT_NE(kept.output.find(" 0 input pixels with a nearer"), std::string::npos)
                << kept.output;
        }
        const test::Outcome bad =
            test::run_reprise(base + q(dir + "/bad") + " --silhouettes thin", 60);
        EXPECT_NE(bad.status, 0) << bad.output;
        EXPECT_NE(bad.output.find("--silhouettes"), std::string::npos) << bad.output;
        EXPECT_FALSE(fs::exists(dir + "/bad")) << command;
        fs::remove_all(dir + "/widen");
        fs::remove_all(dir + "/keep");
    }
    fs::remove_all(dir);
}
