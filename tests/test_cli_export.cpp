// `reprise metrics` and `reprise export` end to end on small EXR sequences.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/core/metrics.hpp"
#include "support/cli.hpp"

using namespace reprise;
namespace fs = std::filesystem;

namespace {

using test::fresh_directory;
using test::run_command;
using test::run_output;

class CliExport : public testing::Test {
protected:
    void SetUp() override {
        root_ = fresh_directory(fs::temp_directory_path() /
                                ("reprise_test_cli_export_" + std::to_string(::getpid()) + "_" +
                                 testing::UnitTest::GetInstance()->current_test_info()->name()));
    }
    void TearDown() override { fs::remove_all(root_); }

    // A bright square moving `speed` pixels right per frame over a gradient, with depth and
    // motion; `noise` perturbs the colour.
    std::string write_sequence(const std::string& name, int frames, int w, int h, float noise = 0,
                               double fps = 24.0) {
        fs::path dir = root_ / name;
        fs::create_directories(dir);
        for (int i = 0; i < frames; ++i) {
            Frame f;
            f.fps = fps;
            f.color.resize(w, h);
            f.depth.assign(w, h, std::numeric_limits<float>::infinity());
            f.motion.resize(w, h);
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    float g = float(x) / w;
                    bool square = x >= 4 + 2 * i && x < 12 + 2 * i && y >= 4 && y < 12;
                    float v = square ? 0.9f : 0.2f * g;
                    float n = noise * float(((x * 7 + y * 13 + i * 5) % 11) - 5) / 5.0f;
                    f.color(x, y) = glm::vec4(v + n, v, v - n, 1.0f);
                    if (y < h - 3) f.depth(x, y) = square ? 2.0f : 10.0f + y;
                    if (square) f.motion(x, y) = {-2.0f, 0.0f};
                }
            if (Status s = write_frame(frame_path(dir.string(), i), f); !s.ok()) {
                ADD_FAILURE() << s.message();
            }
        }
        return dir.string();
    }

    fs::path root_;
};

std::vector<std::string> lines(const fs::path& file) {
    std::ifstream in(file);
    std::vector<std::string> out;
    for (std::string line; std::getline(in, line);) out.push_back(line);
    return out;
}

}  // namespace

TEST(CliMetrics, RejectsBadArguments) {
    using reprise::cli::command_metrics;
    EXPECT_EQ(run_command(command_metrics, {"--help"}), 0);
    EXPECT_EQ(run_command(command_metrics, {"--ref", "a"}), 2);  // no --test
    EXPECT_EQ(run_command(command_metrics, {"--ref", "a", "--test", "b", "--ppd", "0"}), 2);
    EXPECT_EQ(run_command(command_metrics, {"--ref", "/nonexistent/a", "--test", "/nonexistent/b"}),
              1);
}

TEST(CliExportArgs, RejectsBadArguments) {
    using reprise::cli::command_export;
    EXPECT_EQ(run_command(command_export, {"--help"}), 0);
    EXPECT_EQ(run_command(command_export, {}), 2);       // no DIR
    EXPECT_EQ(run_command(command_export, {"dir"}), 2);  // no output
    EXPECT_EQ(run_command(command_export, {"dir", "--png", "a.png", "--mp4", "b.mp4"}), 2);
    EXPECT_EQ(run_command(command_export, {"dir", "--mp4", "b.mp4", "--channel", "albedo"}), 2);
    EXPECT_EQ(run_command(command_export, {"dir", "--mp4", "b.mp4", "--fps", "-3"}), 2);
    EXPECT_EQ(run_command(command_export, {"/nonexistent/seq", "--png", "/tmp/a.png"}), 1);
}

TEST_F(CliExport, MetricsCsvMatchesTheLibrary) {
    std::string ref = write_sequence("ref", 3, 24, 20);
    std::string same = write_sequence("same", 3, 24, 20);
    std::string test = write_sequence("test", 3, 24, 20, 0.05f);
    fs::path csv = root_ / "m.csv";
    ASSERT_EQ(
        run_command(cli::command_metrics, {"--ref", ref, "--test", test, "--csv", csv.string()}),
        0);
    auto rows = lines(csv);
    ASSERT_EQ(rows.size(), 4u);
    EXPECT_EQ(rows[0], "frame,psnr,ssim,flip");

    // Frame 1 recomputed through the library.
    Frame a, b;
    ASSERT_TRUE(read_frame(frame_path(ref, 1), a).ok());
    ASSERT_TRUE(read_frame(frame_path(test, 1), b).ok());
    Image<glm::vec3> da(24, 20), db(24, 20);
    to_display(a.color.view(), da.view());
    to_display(b.color.view(), db.view());
    ImageError e = image_error(da.view(), db.view());
    int frame = -1;
    double p = 0, s = 0, f = 0;
    ASSERT_EQ(std::sscanf(rows[2].c_str(), "%d,%lf,%lf,%lf", &frame, &p, &s, &f), 4) << rows[2];
    EXPECT_EQ(frame, 1);
    EXPECT_NEAR(p, e.psnr, 1e-5);
    EXPECT_NEAR(s, e.ssim, 1e-5);
    EXPECT_NEAR(f, e.flip, 1e-5);
    EXPECT_GT(f, 0.0);

    // Identical sequences: PSNR inf, SSIM 1, FLIP 0.
    ASSERT_EQ(
        run_command(cli::command_metrics, {"--ref", ref, "--test", same, "--csv", csv.string()}),
        0);
    rows = lines(csv);
    ASSERT_EQ(rows.size(), 4u);
    EXPECT_EQ(rows[1], "0,inf,1.000000,0.000000");
}

TEST_F(CliExport, MetricsNamesMismatchedFramesAndMasks) {
    std::string ref = write_sequence("ref", 3, 24, 20);
    std::string shorter = write_sequence("short", 2, 24, 20);
    std::string smaller = write_sequence("small", 3, 24, 18);
    EXPECT_EQ(run_command(cli::command_metrics, {"--ref", ref, "--test", shorter}), 1);
    EXPECT_EQ(run_command(cli::command_metrics, {"--ref", ref, "--test", smaller}), 1);

    std::string noisy = write_sequence("noisy", 3, 24, 20, 0.05f);
    fs::path masks = root_ / "masks";
    fs::create_directories(masks);
    cv::Mat nothing(20, 24, CV_8U, cv::Scalar(0));
    for (int i = 0; i < 3; ++i)
        ASSERT_TRUE(
            cv::imwrite((masks / ("mask_" + std::to_string(i) + ".png")).string(), nothing));
    fs::path csv = root_ / "m.csv";
    ASSERT_EQ(run_command(cli::command_metrics, {"--ref", ref, "--test", noisy, "--mask",
                                                 masks.string(), "--csv", csv.string()}),
              0);
    EXPECT_EQ(lines(csv)[1], "0,nan,nan,nan");  // an all-zero mask selects nothing

    fs::remove(masks / "mask_2.png");
    EXPECT_EQ(run_command(cli::command_metrics,
                          {"--ref", ref, "--test", noisy, "--mask", masks.string()}),
              1);
    cv::Mat wrong(10, 10, CV_8U, cv::Scalar(255));
    ASSERT_TRUE(cv::imwrite((masks / "mask_2.png").string(), wrong));
    EXPECT_EQ(run_command(cli::command_metrics,
                          {"--ref", ref, "--test", noisy, "--mask", masks.string()}),
              1);
}

TEST_F(CliExport, ContactSheetAndPngFolder) {
    std::string seq = write_sequence("seq", 9, 32, 24);
    fs::path sheet = root_ / "sheet.png";
    ASSERT_EQ(run_command(cli::command_export, {seq, "--png", sheet.string()}), 0);
    cv::Mat img = cv::imread(sheet.string());
    ASSERT_FALSE(img.empty());
    // 6 rows of (label 20 + tile 24), 3 columns of 32, gaps of 4.
    EXPECT_EQ(img.cols, 3 * 32 + 4 * 4);
    EXPECT_EQ(img.rows, 6 * (20 + 24) + 7 * 4);

    fs::path out = root_ / "frames";
    ASSERT_EQ(
        run_command(cli::command_export, {seq, "--png", out.string() + "/", "--channel", "depth"}),
        0);
    int count = 0;
    for (const auto& entry : fs::directory_iterator(out))
        count += entry.path().extension() == ".png";
    EXPECT_EQ(count, 9);
    cv::Mat depth = cv::imread((out / "frame_00000.png").string());
    ASSERT_EQ(depth.cols, 32);
    EXPECT_EQ(depth.at<cv::Vec3b>(23, 0), cv::Vec3b(0, 0, 0));       // background
    EXPECT_EQ(depth.at<cv::Vec3b>(5, 5), cv::Vec3b(255, 255, 255));  // nearest: the square

    // A channel the frames lack is an error naming the file.
    EXPECT_EQ(
        run_command(cli::command_export, {seq, "--png", out.string() + "/", "--channel", "normal"}),
        1);
}

TEST_F(CliExport, Mp4HasEveryFrame) {
    if (run_output("command -v ffmpeg").empty() || run_output("command -v ffprobe").empty())
        GTEST_SKIP() << "ffmpeg/ffprobe not installed";
    std::string seq = write_sequence("seq", 7, 31, 21, 0.0f, 12.0);
    fs::path mp4 = root_ / "out.mp4";
    ASSERT_EQ(run_command(cli::command_export, {seq, "--mp4", mp4.string(), "--channel", "motion"}),
              0);
    ASSERT_TRUE(fs::exists(mp4));
    std::string probe = run_output(
        "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
        "stream=nb_read_frames,width,height,r_frame_rate -of default=noprint_wrappers=1 '" +
        mp4.string() + "'");
    EXPECT_NE(probe.find("nb_read_frames=7"), std::string::npos) << probe;
    EXPECT_NE(probe.find("width=32"), std::string::npos) << probe;
    EXPECT_NE(probe.find("r_frame_rate=12/1"), std::string::npos) << probe;

    ASSERT_EQ(run_command(cli::command_export, {seq, "--mp4", mp4.string(), "--fps", "25"}), 0);
    probe = run_output(
        "ffprobe -v error -select_streams v:0 -show_entries stream=r_frame_rate "
        "-of default=noprint_wrappers=1 '" +
        mp4.string() + "'");
    EXPECT_NE(probe.find("r_frame_rate=25/1"), std::string::npos) << probe;
}
