#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "reprise/core/video.hpp"
#include "reprise/core/visualize.hpp"
#include "support/cli.hpp"
#include "support/frames.hpp"

using namespace reprise;
namespace fs = std::filesystem;

namespace {

using test::kInf;
using test::kNaN;
using test::run_output;

fs::path temp_dir(const std::string& name) {
    return test::fresh_directory(fs::temp_directory_path() / ("reprise_test_export_" + name + "_" +
                                                              std::to_string(::getpid())));
}

}  // namespace

TEST(Visualize, ColorIsRoundedDisplayValue) {
    Image<glm::vec4> c(3, 1);
    c(0, 0) = {0.0f, 1.0f, 0.5f, 1.0f};  // 0.5 encodes to 0.73536 = 187.52 / 255
    c(1, 0) = {kNaN, 5.0f, -1.0f, 1.0f};
    Image<Rgb8> out(3, 1);
    visualize_color(c.view(), out.view());
    EXPECT_EQ(out(0, 0), Rgb8(0, 255, 188));
    EXPECT_EQ(out(1, 0), Rgb8(0, 255, 0));
}

TEST(Visualize, DepthIsLogGreyWithBlackBackground) {
    Image<float> d(6, 1);
    d(0, 0) = 1.0f;
    d(1, 0) = 10.0f;
    d(2, 0) = 100.0f;
    d(3, 0) = kInf;
    d(4, 0) = kNaN;
    d(5, 0) = -2.0f;
    DepthRange r = depth_range(d.view());
    EXPECT_EQ(r.near, 1.0f);
    EXPECT_EQ(r.far, 100.0f);
    Image<Rgb8> out(6, 1);
    visualize_depth(d.view(), out.view());
    EXPECT_EQ(out(0, 0), Rgb8(255));
    EXPECT_EQ(out(2, 0), Rgb8(48));
    // Log scale: 10 is halfway between 1 and 100.
    EXPECT_NEAR(out(1, 0).r, (255 + 48) / 2.0, 1.0);
    EXPECT_EQ(out(3, 0), Rgb8(0));
    EXPECT_EQ(out(4, 0), Rgb8(0));
    EXPECT_EQ(out(5, 0), Rgb8(0));
    EXPECT_GT(out(2, 0).r, 0);  // far geometry stays distinguishable from background

    // A fixed range clamps depths beyond it.
    visualize_depth(d.view(), out.view(), {.near = 10.0f, .far = 20.0f});
    EXPECT_EQ(out(0, 0), Rgb8(255));
    EXPECT_EQ(out(1, 0), Rgb8(255));
    EXPECT_EQ(out(2, 0), Rgb8(48));

    Image<float> empty_scene(4, 4, kInf);
    Image<Rgb8> black(4, 4, Rgb8(9));
    visualize_depth(empty_scene.view(), black.view());
    EXPECT_EQ(black, Image<Rgb8>(4, 4, Rgb8(0)));
}

TEST(Visualize, MotionWheel) {
    Image<glm::vec2> m(6, 1);
    m(0, 0) = {0.0f, 0.0f};
    m(1, 0) = {4.0f, 0.0f};   // +x: red
    m(2, 0) = {-8.0f, 0.0f};  // -x, beyond saturation: cyan
    m(3, 0) = {0.0f, 2.0f};   // half saturated
    m(4, 0) = {kNaN, 0.0f};
    m(5, 0) = {kInf, 0.0f};
    EXPECT_EQ(motion_length(m.view()), 8.0f);
    EXPECT_EQ(motion_length(m.view(), 0.0f), 2.0f);  // zero, NaN and inf are left out
    EXPECT_EQ(motion_length(m.view(), 0.5f), 4.0f);
    EXPECT_EQ(motion_length(Image<glm::vec2>(3, 3).view()), 0.0f);
    Image<Rgb8> out(6, 1);
    visualize_motion(m.view(), out.view(), 4.0f);
    EXPECT_EQ(out(0, 0), Rgb8(255));
    EXPECT_EQ(out(1, 0), Rgb8(255, 0, 0));
    EXPECT_EQ(out(2, 0), Rgb8(0, 255, 255));
    EXPECT_EQ(out(3, 0).g, 255);  // hue 90: yellow-green, half saturated
    EXPECT_NEAR(out(3, 0).r, 191, 1);
    EXPECT_NEAR(out(3, 0).b, 128, 1);
    EXPECT_EQ(out(4, 0), Rgb8(0));
    EXPECT_EQ(out(5, 0), Rgb8(255, 0, 0));

    // Automatic saturation at the largest motion: the -8 vector is fully saturated.
    visualize_motion(m.view(), out.view());
    EXPECT_EQ(out(2, 0), Rgb8(0, 255, 255));
    EXPECT_NEAR(out(1, 0).g, 128, 1);
}

TEST(Visualize, NormalsAndIds) {
    Image<glm::vec3> n(3, 1);
    n(0, 0) = {0.0f, 0.0f, 1.0f};
    n(1, 0) = {-1.0f, 0.0f, 0.0f};
    n(2, 0) = {0.0f, 0.0f, 0.0f};
    Image<Rgb8> out(3, 1);
    visualize_normal(n.view(), out.view());
    EXPECT_EQ(out(0, 0), Rgb8(128, 128, 255));
    EXPECT_EQ(out(1, 0), Rgb8(0, 128, 128));
    EXPECT_EQ(out(2, 0), Rgb8(0));

    Image<uint32_t> ids(4, 1);
    ids(0, 0) = 0;
    ids(1, 0) = 1;
    ids(2, 0) = 2;
    ids(3, 0) = 1;
    Image<Rgb8> idc(4, 1);
    visualize_id(ids.view(), idc.view());
    EXPECT_EQ(idc(0, 0), Rgb8(0));
    EXPECT_EQ(idc(1, 0), idc(3, 0));
    EXPECT_NE(idc(1, 0), idc(2, 0));
    // Neighbouring ids get clearly different colours, and none is black.
    int distinct = 0;
    for (uint32_t i = 1; i < 200; ++i) {
        Rgb8 a = id_color(i), b = id_color(i + 1);
        EXPECT_NE(a, Rgb8(0));
        int diff = std::abs(a.r - b.r) + std::abs(a.g - b.g) + std::abs(a.b - b.b);
        distinct += diff > 60;
    }
    EXPECT_GT(distinct, 180);
}

TEST(Visualize, ContactSheetLayoutAndLabels) {
    Image<Rgb8> a(40, 30, Rgb8(200, 0, 0)), b(40, 30, Rgb8(0, 200, 0));
    std::vector<Tile> tiles;
    for (int i = 0; i < 7; ++i)
        tiles.push_back({i % 2 ? b.view() : a.view(), "tile " + std::to_string(i)});
    Image<Rgb8> sheet = contact_sheet(tiles, {.columns = 3, .gap = 4, .label_height = 20});
    EXPECT_EQ(sheet.width(), 3 * 40 + 4 * 4);
    EXPECT_EQ(sheet.height(), 3 * (20 + 30) + 4 * 4);
    // Tile 4 (row 1, column 1) sits under its label strip.
    int x0 = 4 + 1 * 44, y0 = 4 + 1 * 54;
    EXPECT_EQ(sheet(x0 + 20, y0 + 20 + 15), Rgb8(200, 0, 0));
    EXPECT_EQ(sheet(x0 + 39, y0 + 20 + 29), Rgb8(200, 0, 0));
    EXPECT_EQ(sheet(x0 + 41, y0 + 20 + 15), Rgb8(32));  // the gap
    int text_pixels = 0;
    for (int y = y0; y < y0 + 20; ++y)
        for (int x = x0; x < x0 + 40; ++x) text_pixels += sheet(x, y).r > 100;
    EXPECT_GT(text_pixels, 10);
    // The empty cells of the last row stay background.
    EXPECT_EQ(sheet(4 + 2 * 44 + 20, 4 + 2 * 54 + 35), Rgb8(32));

    // Scaled to a tile width, no labels; an empty tile is black.
    tiles = {{a.view(), ""}, {{}, "missing"}};
    sheet = contact_sheet(tiles, {.columns = 2, .tile_width = 20, .gap = 0, .label_height = 0});
    EXPECT_EQ(sheet.width(), 40);
    EXPECT_EQ(sheet.height(), 15);
    EXPECT_EQ(sheet(10, 7), Rgb8(200, 0, 0));
    EXPECT_EQ(sheet(30, 7), Rgb8(0));
}

TEST(Visualize, WritesPng) {
    fs::path dir = temp_dir("png");
    Image<Rgb8> img(5, 3, Rgb8(10, 20, 30));
    img(4, 2) = Rgb8(255, 0, 0);
    ASSERT_TRUE(write_png((dir / "a.png").string(), img.view()).ok());
    cv::Mat back = cv::imread((dir / "a.png").string(), cv::IMREAD_COLOR);
    ASSERT_EQ(back.cols, 5);
    ASSERT_EQ(back.rows, 3);
    EXPECT_EQ(back.at<cv::Vec3b>(0, 0), cv::Vec3b(30, 20, 10));  // OpenCV is BGR
    EXPECT_EQ(back.at<cv::Vec3b>(2, 4), cv::Vec3b(0, 0, 255));
    Status bad = write_png((dir / "no" / "such" / "dir.png").string(), img.view());
    EXPECT_FALSE(bad.ok());
    EXPECT_NE(bad.message().find("dir.png"), std::string::npos);
    EXPECT_FALSE(write_png((dir / "a.unknownext").string(), img.view()).ok());
    fs::remove_all(dir);
}

TEST(Export, EncodesMp4WithOddSizeThroughFfmpeg) {
    if (run_output("command -v ffmpeg").empty() || run_output("command -v ffprobe").empty())
        GTEST_SKIP() << "ffmpeg/ffprobe not installed";
    fs::path dir = temp_dir("mp4");
    const int w = 33, h = 17, n = 12;
    std::vector<Image<Rgb8>> frames;
    for (int i = 0; i < n; ++i) {
        Image<Rgb8> f(w, h, Rgb8(20));
        for (int y = 0; y < h; ++y) f((i * 2) % w, y) = Rgb8(255);
        frames.push_back(f);
    }
    std::vector<ImageView<const Rgb8>> views;
    for (const Image<Rgb8>& f : frames) views.push_back(f.view());
    std::string path = (dir / "out.mp4").string();
    Status s = write_mp4(path, views, {.fps = 24.0});
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_TRUE(fs::exists(path));
    EXPECT_GT(fs::file_size(path), 0u);
    std::string probe = run_output(
        "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
        "stream=nb_read_frames,width,height,r_frame_rate -of default=noprint_wrappers=1 '" +
        path + "'");
    EXPECT_NE(probe.find("nb_read_frames=12"), std::string::npos) << probe;
    EXPECT_NE(probe.find("width=34"), std::string::npos) << probe;
    EXPECT_NE(probe.find("height=18"), std::string::npos) << probe;
    EXPECT_NE(probe.find("r_frame_rate=24/1"), std::string::npos) << probe;
    fs::remove_all(dir);
}

TEST(Export, VideoErrorsAreReportedNotFatal) {
    Image<Rgb8> f(16, 16);
    ImageView<const Rgb8> views[] = {f.view()};
    Status missing = write_mp4("/tmp/x.mp4", views, {.ffmpeg = "reprise-no-such-ffmpeg"});
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.message().find("not found"), std::string::npos) << missing.message();

    EXPECT_FALSE(write_mp4("/tmp/x.mp4", views, {.fps = 0.0}).ok());
    EXPECT_FALSE(write_mp4("/tmp/x.mp4", {}, {}).ok());

    if (run_output("command -v ffmpeg").empty()) GTEST_SKIP() << "ffmpeg not installed";
    // ffmpeg cannot create the file: its failure comes back as a status (no SIGPIPE death),
    // however many frames were pushed before it gave up.
    VideoWriter writer;
    ASSERT_TRUE(writer.open("/nonexistent-dir/x.mp4", 256, 256).ok());
    Image<Rgb8> big(256, 256);
    Status s;
    for (int i = 0; i < 200 && s.ok(); ++i) s = writer.write(big.view());
    if (s.ok()) s = writer.close();
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("x.mp4"), std::string::npos) << s.message();

    VideoWriter sized;
    ASSERT_TRUE(sized.open(testing::TempDir() + "sized.mp4", 16, 16).ok());
    Image<Rgb8> wrong(8, 8);
    EXPECT_FALSE(sized.write(wrong.view()).ok());
    EXPECT_TRUE(sized.write(f.view()).ok());
    EXPECT_TRUE(sized.close().ok());
}
