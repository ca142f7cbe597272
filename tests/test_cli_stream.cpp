// `reprise serve` and `reprise connect` as processes on loopback: frames written with their
// display log; bad arguments refused with one message.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <thread>

#include "support/cli.hpp"

namespace fs = std::filesystem;
using reprise::test::Outcome;
using reprise::test::run_reprise;

TEST(CliStream, ServeAndConnectWriteDisplayedFrames) {
    const fs::path out =
        reprise::test::fresh_directory(fs::temp_directory_path() / "reprise-cli-stream");
    const std::string port = std::to_string(20000 + getpid() % 20000);
    Outcome served;
    std::thread server([&] {
        served = run_reprise(
            "serve --listen 127.0.0.1:" + port + " --pin 7788 --size 96x64 --duration 7", 60);
    });
    const Outcome connected =
        run_reprise("connect 127.0.0.1:" + port +
                        " --pin 7788 --display-rate 30 --duration 3 --out " + out.string(),
                    60);
    server.join();
    EXPECT_EQ(connected.status, 0) << connected.output;
    EXPECT_EQ(served.status, 0) << served.output;
    EXPECT_TRUE(fs::exists(out / "frame_00000.exr")) << connected.output;
    const std::string log = reprise::test::read_text(out / "display.csv");
    EXPECT_EQ(log.rfind("index,scene_time,pose_us,displayed_us,latency_ms", 0), 0u) << log;
    EXPECT_GE(std::count(log.begin(), log.end(), '\n'), 10) << log;
}

TEST(CliStream, BadArgumentsAreRefused) {
    auto expect_refused = [](const std::string& args, const std::string& mention) {
        const Outcome r = run_reprise(args, 30);
        EXPECT_TRUE(r.status == 1 || r.status == 2) << args << ": " << r.status << "\n" << r.output;
        EXPECT_NE(r.output.find(mention), std::string::npos) << args << ":\n" << r.output;
    };
    expect_refused("serve --listen 127.0.0.1:0", "--pin");
    expect_refused("serve --pin 1 --mode sideways", "--mode");
    expect_refused("serve --pin 1 --lowres 3 --mode lowres", "--lowres");
    expect_refused("serve --pin 1 --listen nowhere", "HOST:PORT");
    expect_refused("connect 127.0.0.1:9 --pin 1 --scene ../../etc/passwd --duration 1",
                   "never a path");
    expect_refused("connect 127.0.0.1 --pin 1", "HOST:PORT");
    expect_refused("connect 127.0.0.1:9", "--pin");
}
