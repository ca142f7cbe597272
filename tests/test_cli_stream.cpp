// `reprise serve` and `reprise connect` as processes on loopback: frames written with their
// display log; bad arguments refused with one message.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "frame_writer.hpp"
#include "reprise/codec/codec.hpp"
#include "reprise/core/exr.hpp"
#include "support/cli.hpp"

namespace fs = std::filesystem;
using reprise::test::Outcome;
using reprise::test::run_reprise;

TEST(CliStream, ServeAndConnectWriteDisplayedFrames) {
    const fs::path out =
        reprise::test::fresh_directory(fs::temp_directory_path() / "reprise-cli-stream");
    const std::string port = std::to_string(20000 + getpid() % 20000);
    // The PIN from the environment for the server and from a file for the client (never argv).
    ::setenv("REPRISE_PIN", "778899", 1);
    const fs::path pin_file = out / "pin.txt";
    std::ofstream(pin_file) << "778899\n";
    Outcome served;
    std::thread server([&] {
        served = run_reprise("serve --listen 127.0.0.1:" + port + " --size 96x64 --duration 7", 60);
    });
    const Outcome connected =
        run_reprise("connect 127.0.0.1:" + port + " --pin-file " + pin_file.string() +
                        " --display-rate 30 --duration 3 --out " + out.string(),
                    60);
    ::unsetenv("REPRISE_PIN");
    server.join();
    EXPECT_EQ(connected.status, 0) << connected.output;
    EXPECT_EQ(served.status, 0) << served.output;
    EXPECT_TRUE(fs::exists(out / "frame_00000.exr")) << connected.output;
    const std::string log = reprise::test::read_text(out / "display.csv");
    EXPECT_EQ(log.rfind("index,scene_time,pose_us,displayed_us,latency_ms", 0), 0u) << log;
    EXPECT_GE(std::count(log.begin(), log.end(), '\n'), 10) << log;
}

// --backend gles on a lowres stream: every display frame extrapolated and every frame's colour
// upsampled by the GPU (llvmpipe here), none left to the CPU because the GPU failed; the
// upsampled colour goes to the extrapolation as a texture (nothing downloaded for it), and the
// frames written show the scene (the CPU's copy of that colour is never filled: warping it would
// write black frames).
TEST(CliStream, ConnectExtrapolatesOnTheGpuBackend) {
    const fs::path out =
        reprise::test::fresh_directory(fs::temp_directory_path() / "reprise-cli-stream-gles");
    const std::string port = std::to_string(20000 + (getpid() + 7) % 20000);
    Outcome served;
    std::thread server([&] {
        served = run_reprise("serve --pin 445566 --listen 127.0.0.1:" + port +
                                 " --size 96x64 --duration 5 --mode lowres --lowres 4",
                             60);
    });
    const Outcome connected = run_reprise("connect 127.0.0.1:" + port +
                                              " --pin 445566 --display-rate 30 --duration 2 "
                                              "--backend gles --out " +
                                              out.string(),
                                          60);
    server.join();
    EXPECT_EQ(connected.status, 0) << connected.output;
    EXPECT_EQ(served.status, 0) << served.output;
    EXPECT_NE(connected.output.find("extrapolated on the GPU"), std::string::npos)
        << connected.output;
    EXPECT_NE(connected.output.find("download 0.00 ms a frame; the colour handed to the "
                                    "extrapolation as a texture"),
              std::string::npos)
        << connected.output;
    EXPECT_EQ(connected.output.find("the GPU failed on"), std::string::npos) << connected.output;
    // (Under the sanitizers llvmpipe's upsampling leaves the display loop a frame or two.)
    ASSERT_TRUE(fs::exists(out / "frame_00000.exr")) << connected.output;
    reprise::Frame shown;
    ASSERT_TRUE(reprise::read_frame((out / "frame_00000.exr").string(), shown).ok());
    double sum = 0.0;
    for (std::size_t i = 0; i < shown.color.pixel_count(); ++i)
        sum += shown.color.data()[i].r + shown.color.data()[i].g + shown.color.data()[i].b;
    EXPECT_GT(sum / double(shown.color.pixel_count()), 0.1);  // the scene, not black
}

// --backend gles --window without --out: the window's OpenGL ES context is the GPU's, each
// extrapolated frame is drawn from its texture and nothing is downloaded (SDL's offscreen driver).
// Where SDL offers no OpenGL (its dummy driver) the window falls back to SDL's software renderer
// beside the GPU's own context, and says so.
TEST(CliStream, ConnectWindowDrawsTheGpusFramesWithoutDownloading) {
    const std::string port = std::to_string(20000 + (getpid() + 13) % 20000);
    Outcome served;
    std::thread server([&] {
        served = run_reprise(
            "serve --pin 445566 --listen 127.0.0.1:" + port + " --size 96x64 --duration 9", 60);
    });
    const std::string connect = "connect 127.0.0.1:" + port +
                                " --pin 445566 --display-rate 30 --duration 2 --backend gles "
                                "--window";
    ::setenv("SDL_VIDEODRIVER", "offscreen", 1);
    const Outcome on_gl = run_reprise(connect, 60);
    ::setenv("SDL_VIDEODRIVER", "dummy", 1);
    const Outcome software = run_reprise(connect, 60);
    ::unsetenv("SDL_VIDEODRIVER");
    server.join();
    EXPECT_EQ(served.status, 0) << served.output;
    EXPECT_EQ(on_gl.status, 0) << on_gl.output;
    EXPECT_NE(on_gl.output.find("download 0.00 ms a frame; kept on the GPU and drawn from there "
                                "by the window"),
              std::string::npos)
        << on_gl.output;
    EXPECT_EQ(on_gl.output.find("the GPU failed on"), std::string::npos) << on_gl.output;
    EXPECT_EQ(software.status, 0) << software.output;
    EXPECT_NE(software.output.find("no OpenGL ES window"), std::string::npos) << software.output;
    EXPECT_NE(software.output.find("extrapolated on the GPU"), std::string::npos)
        << software.output;
    EXPECT_EQ(software.output.find("kept on the GPU"), std::string::npos) << software.output;
}

TEST(CliStream, BadArgumentsAreRefused) {
    auto expect_refused = [](const std::string& args, const std::string& mention) {
        const Outcome r = run_reprise(args, 30);
        EXPECT_TRUE(r.status == 1 || r.status == 2) << args << ": " << r.status << "\n" << r.output;
        EXPECT_NE(r.output.find(mention), std::string::npos) << args << ":\n" << r.output;
    };
    expect_refused("serve --listen 127.0.0.1:0", "--pin");
    expect_refused("serve --pin 123456 --mode sideways", "--mode");
    expect_refused("serve --pin 123456 --lowres 3 --mode lowres", "--lowres");
    expect_refused("serve --pin 123456 --listen nowhere", "HOST:PORT");
    expect_refused("connect 127.0.0.1:9 --pin 123456 --scene ../../etc/passwd --duration 1",
                   "never a path");
    expect_refused("connect 127.0.0.1 --pin 123456", "HOST:PORT");
    expect_refused("connect 127.0.0.1:9", "--pin");
    expect_refused("connect 127.0.0.1:9 --pin 123456 --backend cuda --duration 1", "--backend");
    // Short PINs only when asked for; one source of the PIN at a time.
    expect_refused("serve --listen 127.0.0.1:0 --pin 1234 --duration 1", "--allow-weak-pin");
    expect_refused("connect 127.0.0.1:9 --pin 1234 --duration 1", "--allow-weak-pin");
    expect_refused("serve --pin 123456 --pin-file /nonexistent/pin --duration 1", "--pin-file");
    expect_refused("connect 127.0.0.1:9 --pin-file /nonexistent/pin --duration 1", "--pin-file");
    // Durations and ports out of range are refused, not read as "forever" or "off".
    expect_refused("serve --listen 127.0.0.1:0 --pin 123456 --duration 0", "--duration");
    expect_refused("serve --listen 127.0.0.1:0 --pin 123456 --duration -3", "--duration");
    expect_refused("serve --listen 127.0.0.1:0 --pin 123456 --duration 1 --metrics-port -5",
                   "--metrics-port");
    expect_refused("connect 127.0.0.1:9 --pin 123456 --duration 0", "--duration");
}

TEST(CliStream, WeakPinIsAllowedOnRequestAndListeningBeyondLoopbackWarns) {
    const Outcome weak = run_reprise(
        "serve --listen 127.0.0.1:0 --pin 1234 --allow-weak-pin --size 32x32 "
        "--duration 0.3",
        30);
    EXPECT_EQ(weak.status, 0) << weak.output;
    // 192.0.2.1 (TEST-NET-1) is not this machine's: the bind fails after the warning, and nothing
    // leaves loopback.
    const Outcome wide =
        run_reprise("serve --listen 192.0.2.1:0 --pin 123456 --size 32x32 --duration 0.3", 30);
    EXPECT_NE(wide.output.find("warning: listening on 192.0.2.1"), std::string::npos)
        << wide.output;
}

TEST(CliStream, AStreamFileWithReservedHeaderBytesSetIsRefused) {
    const fs::path dir =
        reprise::test::fresh_directory(fs::temp_directory_path() / "reprise-cli-reserved");
    std::vector<uint8_t> header;
    ASSERT_TRUE(reprise::codec::write_stream_header(header, 16, 16, 0.0).ok());
    ASSERT_EQ(header.size(), 24u);
    auto write = [&](const fs::path& p) {
        std::ofstream(p, std::ios::binary)
            .write(reinterpret_cast<const char*>(header.data()), std::streamsize(header.size()));
    };
    write(dir / "clean.rps");
    const Outcome clean = run_reprise("info " + (dir / "clean.rps").string(), 30);
    EXPECT_EQ(clean.status, 0) << clean.output;
    for (std::size_t at : {5, 6, 7}) {
        header[5] = header[6] = header[7] = 0;
        header[at] = 1;
        write(dir / "reserved.rps");
        const Outcome r = run_reprise("info " + (dir / "reserved.rps").string(), 30);
        EXPECT_EQ(r.status, 1) << r.output;
        EXPECT_NE(r.output.find("reserved"), std::string::npos) << r.output;
    }
}

// Issue 23: --out wrote each EXR on the display path. The writer's thread takes it; a full queue
// drops writes (counted) and never holds the caller.
TEST(CliStream, TheFrameWriterNeverHoldsTheDisplayLoop) {
    const fs::path out =
        reprise::test::fresh_directory(fs::temp_directory_path() / "reprise-frame-writer");
    std::atomic<int> calls{0};
    reprise::cli::FrameWriter writer(out.string(), 4,
                                     [&](const std::string&, const reprise::Frame&) {
                                         std::this_thread::sleep_for(std::chrono::milliseconds(50));
                                         ++calls;
                                         return reprise::Status{};
                                     });
    reprise::Frame f;
    f.color.resize(320, 180);
    f.depth.resize(320, 180);
    f.motion.resize(320, 180);
    const auto start = std::chrono::steady_clock::now();
    std::size_t accepted = 0;
    for (int i = 0; i < 40; ++i) accepted += writer.submit(f, i, i / 60.0, 60.0);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ASSERT_TRUE(writer.finish().ok());
    // Writing on the caller's thread would take 40 × 50 ms = 2 s.
    EXPECT_LT(seconds, 1.0);
    EXPECT_EQ(writer.written(), accepted);
    EXPECT_EQ(writer.written() + writer.dropped(), 40u);
    EXPECT_GT(writer.dropped(), 0u);
    EXPECT_EQ(calls.load(), int(accepted));
}

TEST(CliStream, ASecondClientOverMaxSessionsIsToldTheServerIsFull) {
    const std::string port = std::to_string(20000 + (getpid() + 7) % 20000);
    ::setenv("REPRISE_PIN", "778899", 1);
    Outcome served, first;
    std::thread server([&] {
        served = run_reprise("serve --listen 127.0.0.1:" + port +
                                 " --size 64x48 --aa 1 --max-sessions 1 --duration 8",
                             60);
    });
    std::thread one([&] {
        first = run_reprise("connect 127.0.0.1:" + port + " --display-rate 30 --duration 6", 60);
    });
    std::this_thread::sleep_for(std::chrono::seconds(3));
    const auto start = std::chrono::steady_clock::now();
    const Outcome second =
        run_reprise("connect 127.0.0.1:" + port + " --display-rate 30 --duration 6", 60);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    one.join();
    server.join();
    ::unsetenv("REPRISE_PIN");
    EXPECT_EQ(first.status, 0) << first.output;
    EXPECT_EQ(second.status, 1) << second.output;
    EXPECT_NE(second.output.find("server full: 1 sessions"), std::string::npos) << second.output;
    EXPECT_LT(seconds, 4.0) << "told, not timed out after its 6 s";
    EXPECT_EQ(served.output.find(" 0 refused (server full)"), std::string::npos) << served.output;
}

// Both cores kept busy by other threads and 2000 garbage datagrams at the port: a correct client
// shows its first frame within 1 s and from then on at least 90 % of its display frames (the
// single-threaded server showed none: issue 23). Measured 0.07-0.1 s in release and under ASan;
// with llvmpipe's anisotropic filtering the first session frame took about 1.1 s.
TEST(CliStream, AClientIsServedWhileBothCoresAreBusy) {
    const fs::path out =
        reprise::test::fresh_directory(fs::temp_directory_path() / "reprise-cli-stream-busy");
    const int port = 20000 + (getpid() + 13) % 20000;
    ::setenv("REPRISE_PIN", "778899", 1);
    std::atomic<bool> busy{true};
    std::vector<std::thread> load;
    for (int i = 0; i < 2; ++i)
        load.emplace_back([&] {
            volatile uint64_t x = 0;
            while (busy.load(std::memory_order_relaxed)) x = x * 6364136223846793005ull + 1;
        });
    Outcome served;
    std::thread server([&] {
        served = run_reprise(
            "serve --listen 127.0.0.1:" + std::to_string(port) + " --size 96x64 --duration 10", 60);
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(2500));
    const int sock = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(uint16_t(port));
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    uint8_t garbage[64];
    for (int i = 0; i < 2000; ++i) {
        for (int k = 0; k < 64; ++k) garbage[k] = uint8_t(i * 31 + k * 7);
        ::sendto(sock, garbage, 12 + i % 52, 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to));
    }
    ::close(sock);
    const Outcome connected =
        run_reprise("connect 127.0.0.1:" + std::to_string(port) +
                        " --display-rate 30 --duration 4 --out " + out.string(),
                    60);
    busy = false;
    for (std::thread& t : load) t.join();
    server.join();
    ::unsetenv("REPRISE_PIN");
    ASSERT_EQ(connected.status, 0) << connected.output;
    std::istringstream log(reprise::test::read_text(out / "display.csv"));
    std::string row;
    std::getline(log, row);  // header
    double first = -1.0;
    int shown = 0;
    while (std::getline(log, row)) {
        if (first < 0) first = std::atof(row.c_str() + row.find(',') + 1);
        ++shown;
    }
    EXPECT_GE(first, 0.0) << connected.output;
    EXPECT_LE(first, 1.0) << "first frame shown at " << first << " s\n"
                          << connected.output << served.output;
    EXPECT_GE(shown, int(0.9 * (4.0 - first) * 30)) << connected.output << served.output;
}
