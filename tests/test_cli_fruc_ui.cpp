// `reprise fruc` with a UI layer (in-frame channels or `--ui DIR`) and with `--warp auto`.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "commands.hpp"
#include "reprise/core/exr.hpp"
#include "support/cli.hpp"
#include "support/frames.hpp"

using namespace reprise;
namespace fs = std::filesystem;

TEST(CliFrucUi, UiChannelsOrFolderAndAutoChoice) {
    const fs::path dir =
        fs::temp_directory_path() / ("reprise_cli_fruc_ui_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    const std::string rendered = (dir / "hud").string(), scene = (dir / "scene").string(),
                      ui = (dir / "ui").string();
    ASSERT_EQ(test::run_command(cli::command_render, {"--scene", "hud", "--frames", "3", "--fps",
                                                      "30", "--size", "160x90", "--out", rendered}),
              0);
    fs::create_directories(scene);
    fs::create_directories(ui);
    for (int i = 0; i < 3; ++i) {
        Frame f, layer;
        ASSERT_TRUE(read_frame(frame_path(rendered, i), f).ok());
        ASSERT_FALSE(f.ui.empty()) << "the hud scene writes ui.* channels";
        layer.color = f.ui;
        f.ui.clear();
        ASSERT_TRUE(write_frame(frame_path(scene, i), f).ok());
        ASSERT_TRUE(write_frame(frame_path(ui, i), layer).ok());
    }
    const std::string in_frames = (dir / "a").string(), beside = (dir / "b").string();
    test::Outcome r = test::run_reprise(
        "fruc --in " + rendered + " --warp auto --fill auto --out " + in_frames, 120);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("UI layer found"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("2 made frames took the nearest input's UI"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("auto (cheapest"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("chosen"), std::string::npos) << r.output;
    r = test::run_reprise(
        "fruc --in " + scene + " --ui " + ui + " --warp auto --fill auto --out " + beside, 120);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("UI layer found (" + ui), std::string::npos) << r.output;
    for (int k = 0; k < 5; ++k) {
        Frame a, b;
        ASSERT_TRUE(read_frame(frame_path(in_frames, k), a).ok());
        ASSERT_TRUE(read_frame(frame_path(beside, k), b).ok());
        EXPECT_TRUE(test::same_bits(a.ui, b.ui)) << k;
        EXPECT_TRUE(test::same_bits(a.color, b.color)) << k;
    }
    r = test::run_reprise(
        "fruc --in " + scene + " --ui " + (dir / "none").string() + " --out " + beside, 60);
    EXPECT_NE(r.status, 0) << r.output;
    fs::remove_all(dir);
}
