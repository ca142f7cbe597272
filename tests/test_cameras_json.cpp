// cameras.json: the cameras of a sequence whose frames carry none (Blender renders).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <string>

#include "reprise/core/exr.hpp"
#include "support/cli.hpp"
#include "support/frames.hpp"

namespace fs = std::filesystem;
using namespace reprise;

namespace {

std::string numbers(const glm::mat4& m) {
    std::string s = "[";
    for (int i = 0; i < 16; ++i) {
        if (i) s += ',';
        s += std::to_string(m[i / 4][i % 4]);
    }
    return s + "]";
}

std::string entry(const std::string& file, const Camera& c) {
    return "{\"file\":\"" + file + "\",\"time\":" + std::to_string(c.time) +
           ",\"view\":" + numbers(c.view) + ",\"projection\":" + numbers(c.projection) +
           ",\"prev_view\":" + numbers(c.prev_view) +
           ",\"prev_projection\":" + numbers(c.prev_projection) +
           ",\"near\":" + std::to_string(c.near) + ",\"far\":" + std::to_string(c.far) + "}";
}

Camera camera_at(float x) {
    Camera c;
    c.view = glm::lookAt(glm::vec3(x, 1, 5), glm::vec3(0), glm::vec3(0, 1, 0));
    c.prev_view = glm::lookAt(glm::vec3(x - 0.1f, 1, 5), glm::vec3(0), glm::vec3(0, 1, 0));
    c.projection = c.prev_projection = glm::perspective(0.8f, 16.0f / 9.0f, 0.25f, 50.0f);
    c.near = 0.25f, c.far = 50.0f, c.time = x;
    return c;
}

class CamerasJson : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = test::fresh_directory(
            fs::temp_directory_path() /
            ("reprise_cameras_" + std::to_string(::getpid()) + "_" + info->name()));
        for (const char* name : {"0001.exr", "0002.exr"})
            ASSERT_TRUE(write_frame((dir_ / name).string(), test::flat_frame(8, 4, 3.0f, {})).ok());
    }
    void TearDown() override { fs::remove_all(dir_); }
    void write_json(const std::string& text) { std::ofstream((dir_ / "cameras.json")) << text; }
    Status open(Sequence& seq) { return open_sequence(dir_.string(), seq); }

    fs::path dir_;
};

TEST_F(CamerasJson, FramesWithoutCamerasGetThemByFileName) {
    const Camera a = camera_at(0.0f), b = camera_at(0.5f);
    // Listed out of order, with a frame this folder does not hold.
    write_json("{\"frames\":[" + entry("0002.exr", b) + "," + entry("9999.exr", a) + "," +
               entry("0001.exr", a) + "]}");
    Sequence seq;
    ASSERT_TRUE(open(seq).ok());
    ASSERT_EQ(seq.cameras.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        Frame f;
        ASSERT_TRUE(read_frame(seq, i, f).ok());
        const Camera& want = i ? b : a;
        for (int k = 0; k < 16; ++k) {
            EXPECT_NEAR(f.camera.view[k / 4][k % 4], want.view[k / 4][k % 4], 1e-6f);
            EXPECT_NEAR(f.camera.projection[k / 4][k % 4], want.projection[k / 4][k % 4], 1e-6f);
            EXPECT_NEAR(f.camera.prev_view[k / 4][k % 4], want.prev_view[k / 4][k % 4], 1e-6f);
        }
        EXPECT_FLOAT_EQ(f.camera.near, 0.25f);
        EXPECT_FLOAT_EQ(f.camera.far, 50.0f);
        EXPECT_NEAR(f.camera.time, want.time, 1e-6);
    }
}

TEST_F(CamerasJson, TheCutFlagIsReadAndUnknownWhenAbsent) {
    const std::string a = entry("0001.exr", camera_at(0.0f)),
                      b = entry("0002.exr", camera_at(0.5f));
    for (const auto& [cut, want] : {std::pair<std::string, Cut>{",\"cut\":true}", Cut::Yes},
                                    {",\"cut\":false}", Cut::No},
                                    {"}", Cut::Unknown}}) {
        write_json("{\"frames\":[" + a + "," + b.substr(0, b.size() - 1) + cut + "]}");
        Sequence seq;
        ASSERT_TRUE(open(seq).ok());
        Frame f;
        ASSERT_TRUE(read_frame(seq, 1, f).ok());
        EXPECT_EQ(f.camera.cut, want) << cut;
        ASSERT_TRUE(read_frame(seq, 0, f).ok());
        EXPECT_EQ(f.camera.cut, Cut::Unknown);
    }
}

TEST_F(CamerasJson, AFrameCarryingItsCameraKeepsIt) {
    Frame own = test::flat_frame(8, 4, 3.0f, {});
    own.camera = camera_at(2.0f);
    ASSERT_TRUE(write_frame((dir_ / "0001.exr").string(), own).ok());
    write_json("{\"frames\":[" + entry("0001.exr", camera_at(0.0f)) + "]}");
    Sequence seq;
    ASSERT_TRUE(open(seq).ok());
    Frame f;
    ASSERT_TRUE(read_frame(seq, 0, f).ok());
    EXPECT_NEAR(f.camera.time, 2.0, 1e-9);
    ASSERT_TRUE(read_frame(seq, 1, f).ok());
    EXPECT_FALSE(has_projection(f.camera)) << "0002.exr is not listed";
}

TEST_F(CamerasJson, BadFilesAreRefusedNamingWhatAndWhere) {
    const std::string good = entry("0001.exr", camera_at(0.0f));
    std::string identity = good;
    identity.replace(identity.find("\"projection\":") + 13, numbers(camera_at(0).projection).size(),
                     numbers(glm::mat4(1.0f)));
    const std::pair<std::string, std::string> cases[] = {
        {"{\"frames\":[", "not valid JSON"},
        {"[1,2,3]", "\"frames\" array"},
        {"{\"frames\":[{\"view\":[]}]}", "frames[0]: expected an object with a \"file\""},
        {"{\"frames\":[{\"file\":\"0001.exr\",\"view\":[1,2,3]}]}", "16 numbers"},
        {"{\"frames\":[" + good + ",{\"file\":\"0002.exr\"}]}", "frames[1]: no \"view\""},
        {"{\"frames\":[" + identity + "]}", "identity or singular"},
        {"{\"frames\":[" + good.substr(0, good.size() - 1) + ",\"near\":\"x\"}]}",
         "\"near\" is not a finite number"},
        {"{\"frames\":[" + good.substr(0, good.size() - 1) + ",\"near\":60}]}", "near < far"},
        {"{\"frames\":[" + good.substr(0, good.size() - 1) + ",\"cut\":1}]}",
         "frames[0]: \"cut\" must be true or false"},
        {"{\"frames\":[" + good.substr(0, good.size() - 1) + ",\"time\":1e999}]}",
         "not valid JSON"},
    };
    for (const auto& [text, message] : cases) {
        write_json(text);
        Sequence seq;
        const Status s = open(seq);
        ASSERT_FALSE(s.ok()) << text;
        EXPECT_NE(s.message().find("cameras.json"), std::string::npos) << s.message();
        EXPECT_NE(s.message().find(message), std::string::npos) << s.message();
    }
}

}  // namespace
