// `reprise encode`, `decode` and `info FILE.rps` end to end: the stream does not depend on the
// thread count, decoding gives back the encoder's pictures, and damaged files fail clearly.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "commands.hpp"
#include "reprise/codec/codec.hpp"
#include "reprise/core/exr.hpp"
#include "support/cli.hpp"
#include "support/frames.hpp"

using namespace reprise;
namespace fs = std::filesystem;

namespace {

std::string bytes_of(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

}  // namespace

TEST(CliCodec, EncodeDecodeInfoAndThreadCountIndependence) {
    const fs::path dir = test::fresh_directory(fs::temp_directory_path() /
                                               ("reprise_cli_codec_" + std::to_string(::getpid())));
    const std::string frames = (dir / "frames").string();
    ASSERT_EQ(test::run_command(cli::command_render, {"--scene", "crossing", "--frames", "4",
                                                      "--size", "160x96", "--out", frames}),
              0);
    const std::string one = (dir / "one.rps").string(), two = (dir / "two.rps").string();
    const std::string per_frame = (dir / "frames.csv").string();
    const test::Outcome a = test::run_reprise(
        "encode --in " + frames + " --out " + one + " --qp 24 --frame-stats " + per_frame, 120);
    ASSERT_EQ(a.status, 0) << a.output;
    EXPECT_NE(a.output.find("colour"), std::string::npos) << a.output;
    EXPECT_NE(a.output.find("skipped"), std::string::npos) << a.output;
    // The same stream with one worker thread and with four.
    const test::Outcome b =
        test::run_reprise("encode --in " + frames + " --out " + two + " --qp 24", 120);
    ASSERT_EQ(b.status, 0);
    ASSERT_EQ(::setenv("REPRISE_THREADS", "1", 1), 0);
    const test::Outcome c = test::run_reprise(
        "encode --in " + frames + " --out " + (dir / "t1.rps").string() + " --qp 24", 120);
    ASSERT_EQ(::setenv("REPRISE_THREADS", "4", 1), 0);
    const test::Outcome d = test::run_reprise(
        "encode --in " + frames + " --out " + (dir / "t4.rps").string() + " --qp 24", 120);
    ::unsetenv("REPRISE_THREADS");
    ASSERT_EQ(c.status, 0);
    ASSERT_EQ(d.status, 0);
    const std::string stream = bytes_of(one);
    EXPECT_GT(stream.size(), 1000u);
    // --frame-stats: a row per frame, its packet's bytes (the file adds its 24-byte header) and
    // the bits of its sections within them.
    std::ifstream rows(per_frame);
    std::string row;
    std::getline(rows, row);
    EXPECT_EQ(row.rfind("frame,type,bytes,header_bits,camera_bits,depth_bits,motion_bits,", 0), 0u);
    std::size_t packets = 0, bytes = 0;
    while (std::getline(rows, row)) {
        int frame = -1;
        char type[8] = {};
        std::size_t size = 0, bits[5] = {};
        ASSERT_EQ(std::sscanf(row.c_str(), "%d,%7[a-z],%zu,%zu,%zu,%zu,%zu,%zu", &frame, type,
                              &size, &bits[0], &bits[1], &bits[2], &bits[3], &bits[4]),
                  8)
            << row;
        EXPECT_EQ(frame, int(packets));
        EXPECT_STREQ(type, packets == 0 ? "key" : "inter");
        EXPECT_EQ(bits[0] + bits[1] + bits[2] + bits[3] + bits[4], 8 * size) << row;
        EXPECT_GT(bits[2], 0u) << row;
        ++packets, bytes += size;
    }
    EXPECT_EQ(packets, 4u);
    EXPECT_EQ(bytes + 24, stream.size());
    EXPECT_EQ(stream, bytes_of(two));
    // At qp 46 the bounds follow the quantiser (4x) unless --fixed-bounds: a smaller stream of a
    // scene whose depth costs more than its motion (crossing's coarser depth costs it motion:
    // 11,008 against 10,928 bits at this size).
    const std::string stroll = (dir / "stroll").string();
    ASSERT_EQ(test::run_command(cli::command_render, {"--scene", "stroll", "--frames", "4",
                                                      "--size", "160x96", "--out", stroll}),
              0);
    const std::string coarse = (dir / "coarse.rps").string(), fixed = (dir / "fixed.rps").string();
    ASSERT_EQ(
        test::run_reprise("encode --in " + stroll + " --out " + coarse + " --qp 46", 120).status,
        0);
    ASSERT_EQ(test::run_reprise(
                  "encode --in " + stroll + " --out " + fixed + " --qp 46 --fixed-bounds", 120)
                  .status,
              0);
    EXPECT_LT(fs::file_size(coarse), fs::file_size(fixed));
    EXPECT_EQ(stream, bytes_of(dir / "t1.rps")) << "1 thread";
    EXPECT_EQ(stream, bytes_of(dir / "t4.rps")) << "4 threads";

    const std::string decoded = (dir / "decoded").string();
    const test::Outcome e = test::run_reprise("decode " + one + " --out " + decoded, 120);
    ASSERT_EQ(e.status, 0) << e.output;
    Frame source, back;
    ASSERT_TRUE(read_frame(frame_path(frames, 3), source).ok());
    ASSERT_TRUE(read_frame(frame_path(decoded, 3), back).ok());
    // The default depth is the view bound: 0.25 px for displacements up to 0.164, background exact.
    const codec::ViewDepthError view = codec::measure_view_depth_error(
        source.camera, source.depth.view(), back.depth.view(), 0.164f);
    EXPECT_EQ(view.background_mismatches, 0u);
    EXPECT_GT(view.pixels, 0u);
    EXPECT_LE(view.max_px, 0.25);
    const std::string exact = (dir / "lossless.rps").string();
    ASSERT_EQ(
        test::run_reprise("encode --in " + frames + " --out " + exact + " --depth lossless", 120)
            .status,
        0);
    ASSERT_EQ(
        test::run_reprise("decode " + exact + " --out " + (dir / "exact").string(), 120).status, 0);
    ASSERT_TRUE(read_frame(frame_path((dir / "exact").string(), 3), back).ok());
    EXPECT_TRUE(test::same_bits(source.depth, back.depth));
    EXPECT_EQ(test::run_reprise(
                  "encode --in " + frames + " --out " + exact + " --depth view:0.5,0.2", 120)
                  .status,
              0);
    EXPECT_GT(test::display_psnr(source.color, back.color), 31.0);
    EXPECT_EQ(back.camera.view, source.camera.view);

    const test::Outcome info = test::run_reprise("info " + one, 60);
    ASSERT_EQ(info.status, 0) << info.output;
    EXPECT_NE(info.output.find("160x96"), std::string::npos) << info.output;
    EXPECT_NE(info.output.find("key frames: 1"), std::string::npos) << info.output;

    // A damaged byte in the last packet: that packet is skipped by name, the rest decode, exit 1.
    std::string damaged = stream;
    damaged[damaged.size() - 5] ^= 0x40;
    const fs::path bad = dir / "bad.rps";
    std::ofstream(bad, std::ios::binary) << damaged;
    const test::Outcome f =
        test::run_reprise("decode " + bad.string() + " --out " + (dir / "bad").string(), 60);
    EXPECT_EQ(f.status, 1) << f.output;
    EXPECT_NE(f.output.find("packet 3"), std::string::npos) << f.output;
    EXPECT_NE(f.output.find("CRC"), std::string::npos) << f.output;
    EXPECT_TRUE(fs::exists(frame_path((dir / "bad").string(), 2)));
    // Truncated, not a stream, bad arguments.
    std::ofstream(dir / "short.rps", std::ios::binary) << stream.substr(0, stream.size() / 2);
    const test::Outcome g = test::run_reprise(
        "decode " + (dir / "short.rps").string() + " --out " + (dir / "s").string(), 60);
    EXPECT_EQ(g.status, 1) << g.output;
    EXPECT_NE(g.output.find("runs past the end"), std::string::npos) << g.output;
    const test::Outcome h = test::run_reprise(
        "info " + frame_path(frames, 0).substr(0, 0) + (dir / "frames" / "x.rps").string(), 60);
    EXPECT_EQ(h.status, 1) << h.output;
    EXPECT_EQ(test::run_reprise("encode --in " + frames + " --out " + one + " --qp 60", 60).status,
              2);
    EXPECT_EQ(
        test::run_reprise("encode --in " + frames + " --out " + one + " --depth bounded:7", 60)
            .status,
        2);
    for (const char* mode : {"view:0", "view:", "view:0.25,", "view:0.25,-1", "view:x", "viewy"})
        EXPECT_EQ(
            test::run_reprise("encode --in " + frames + " --out " + one + " --depth " + mode, 60)
                .status,
            2)
            << mode;
    fs::remove_all(dir);
}

// A damaged file: every decodable frame is written under its own number, bit-identical to the
// undamaged decode; one line says which bytes were skipped and which frames are missing; exit 1.
// --slices: more slices for many-core decoders, decoded as any stream; out of range refused.
TEST(CliCodec, SlicesAreChosenOrRefused) {
    const fs::path dir = test::fresh_directory(
        fs::temp_directory_path() / ("reprise_cli_slices_" + std::to_string(::getpid())));
    const std::string frames = (dir / "frames").string(), stream = (dir / "s.rps").string();
    ASSERT_EQ(test::run_command(cli::command_render, {"--scene", "pan", "--frames", "2", "--size",
                                                      "64x64", "--out", frames}),
              0);
    const test::Outcome four =
        test::run_reprise("encode --in " + frames + " --out " + stream + " --slices 4", 120);
    ASSERT_EQ(four.status, 0) << four.output;
    const test::Outcome decoded =
        test::run_reprise("decode " + stream + " --out " + (dir / "d").string(), 120);
    EXPECT_EQ(decoded.status, 0) << decoded.output;
    const test::Outcome bad = test::run_reprise(
        "encode --in " + frames + " --out " + (dir / "t.rps").string() + " --slices 65", 120);
    EXPECT_EQ(bad.status, 2) << bad.output;
    EXPECT_NE(bad.output.find("--slices"), std::string::npos) << bad.output;
    fs::remove_all(dir);
}

TEST(CliCodec, DecodeWritesEveryDecodableFrameOfADamagedStream) {
    const fs::path dir = test::fresh_directory(
        fs::temp_directory_path() / ("reprise_cli_recover_" + std::to_string(::getpid())));
    const std::string frames = (dir / "frames").string(), rps = (dir / "s.rps").string();
    ASSERT_EQ(test::run_command(cli::command_render, {"--scene", "crossing", "--frames", "8",
                                                      "--size", "96x64", "--out", frames}),
              0);
    const test::Outcome e =
        test::run_reprise("encode --in " + frames + " --out " + rps + " --keyint 4", 120);
    ASSERT_EQ(e.status, 0) << e.output;
    const std::string intact = (dir / "intact").string();
    ASSERT_EQ(test::run_reprise("decode " + rps + " --out " + intact, 120).status, 0);
    std::string stream = bytes_of(rps);
    std::vector<std::size_t> offsets;  // of each packet
    {
        const std::span<const uint8_t> file(reinterpret_cast<const uint8_t*>(stream.data()),
                                            stream.size());
        codec::StreamInfo info;
        std::vector<std::span<const uint8_t>> packets;
        ASSERT_TRUE(codec::split_stream(file, info, packets).ok());
        for (const auto& p : packets) offsets.push_back(std::size_t(p.data() - file.data()));
    }
    ASSERT_EQ(offsets.size(), 8u);
    // Frame 2 damaged (3 predicted from it, 4 a key frame), the file cut inside frame 7.
    stream[offsets[2] + 40] ^= 0x04;
    const std::size_t cut = offsets[7] + 50;
    stream.resize(cut);
    const fs::path bad = dir / "bad.rps";
    std::ofstream(bad, std::ios::binary) << stream;
    const std::string out = (dir / "out").string();
    const test::Outcome d = test::run_reprise("decode " + bad.string() + " --out " + out, 120);
    EXPECT_EQ(d.status, 1) << d.output;
    const std::string expected =
        "damaged stream: " + std::to_string(offsets[3] - offsets[2] + 50) +
        " bytes skipped: " + std::to_string(offsets[3] - offsets[2]) + " at byte " +
        std::to_string(offsets[2]) + " (packet 2: CRC mismatch), 50 at byte " +
        std::to_string(offsets[7]) +
        " (packet header of frame 7: runs past the end of the file (payload length ";
    EXPECT_NE(d.output.find(expected), std::string::npos) << d.output;
    EXPECT_NE(d.output.find("frames not decoded: 2 (in the damaged bytes), 3 (reference not "
                            "decoded), after 6 (in the damaged bytes); 5 frames decoded; 5 "
                            "frames written to " +
                            out + "\n"),
              std::string::npos)
        << d.output;
    for (int i = 0; i < 8; ++i) {
        const bool written = i == 0 || i == 1 || (i >= 4 && i <= 6);
        EXPECT_EQ(fs::exists(frame_path(out, i)), written) << "frame " << i;
        if (!written) continue;
        Frame a, b;
        ASSERT_TRUE(read_frame(frame_path(intact, i), a).ok());
        ASSERT_TRUE(read_frame(frame_path(out, i), b).ok());
        EXPECT_TRUE(test::same_bits(a.color, b.color)) << "frame " << i;
        EXPECT_TRUE(test::same_bits(a.depth, b.depth)) << "frame " << i;
        EXPECT_TRUE(test::same_bits(a.motion, b.motion)) << "frame " << i;
    }
    // `info` lists the damage.
    const test::Outcome info = test::run_reprise("info " + bad.string(), 60);
    EXPECT_EQ(info.status, 1) << info.output;
    EXPECT_NE(info.output.find("damaged: 50 bytes at byte " + std::to_string(offsets[7])),
              std::string::npos)
        << info.output;
    fs::remove_all(dir);
}
