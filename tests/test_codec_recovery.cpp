// Damaged .rps files: the reader resynchronises on the next valid packet, every decodable frame
// comes out bit-identical to the undamaged decode, and the report names what was lost.
#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <random>

#include "reprise/codec/codec.hpp"
#include "support/frames.hpp"

using namespace reprise;
using namespace reprise::codec;

namespace {

constexpr int kFrames = 12;

// Twelve 64x48 frames with a key frame every 5 (0, 5, 10); each packet's offset in the file.
struct Stream {
    std::vector<uint8_t> file;
    std::vector<std::size_t> offsets;
};

Stream make_stream() {
    Stream s;
    EXPECT_TRUE(write_stream_header(s.file, 64, 48, 30.0).ok());
    Encoder encoder;
    EXPECT_TRUE(
        Encoder::create(EncoderOptions{.qp = 30, .keyint = 5, .detect_cuts = false}, encoder).ok());
    for (int i = 0; i < kFrames; ++i) {
        Frame f = test::flat_frame(64, 48, 5.0f, {0.0f, 0.0f}, uint32_t(i + 1));
        f.camera.time = i / 30.0;
        EXPECT_TRUE(encoder.send_frame(f).ok());
        Packet p;
        EXPECT_EQ(encoder.receive_packet(p), Result::Ok);
        EXPECT_EQ(p.type == PacketType::Key, i % 5 == 0) << i;
        s.offsets.push_back(s.file.size());
        s.file.insert(s.file.end(), p.data.begin(), p.data.end());
    }
    return s;
}

struct Decoded {
    std::map<uint32_t, Frame> frames;
    StreamReport report;
};

Decoded decode(const std::vector<uint8_t>& file) {
    Decoded d;
    Decoder decoder;
    StreamInfo info;
    const Status s = decode_stream(file, decoder, info, d.report, [&](uint32_t n, Frame& f) {
        EXPECT_FALSE(d.frames.count(n)) << "frame " << n << " twice";
        d.frames[n] = f;
        return Status{};
    });
    EXPECT_TRUE(s.ok()) << s.message();
    return d;
}

// The frames that came out are `expected`, each the same bits as in the undamaged decode.
void expect_frames(const Decoded& damaged, const std::vector<uint32_t>& expected) {
    static const Decoded intact = decode(make_stream().file);
    ASSERT_EQ(intact.frames.size(), std::size_t(kFrames));
    std::vector<uint32_t> got;
    for (const auto& [n, f] : damaged.frames) {
        got.push_back(n);
        const Frame& want = intact.frames.at(n);
        EXPECT_TRUE(test::same_bits(f.color, want.color)) << "frame " << n;
        EXPECT_TRUE(test::same_bits(f.depth, want.depth)) << "frame " << n;
        EXPECT_TRUE(test::same_bits(f.motion, want.motion)) << "frame " << n;
        EXPECT_EQ(f.camera.time, want.camera.time) << "frame " << n;
    }
    EXPECT_EQ(got, expected);
    EXPECT_EQ(damaged.report.frames, expected.size());
}

void expect_lost(const LostFrames& l, uint32_t first, uint32_t last, bool open,
                 const std::string& reason) {
    EXPECT_EQ(l.first, first);
    if (!open) {
        EXPECT_EQ(l.last, last);
    }
    EXPECT_EQ(l.open, open);
    EXPECT_EQ(l.reason, reason);
}

// The payload length of the packet at `at` (the fifth varint after magic, version and type):
// its offset and byte count.
std::pair<std::size_t, std::size_t> length_field(const std::vector<uint8_t>& file, std::size_t at) {
    std::size_t pos = at + 6;
    for (int field = 0; field < 4; ++field)
        while (file[pos++] & 0x80) {
        }
    std::size_t end = pos;
    while (file[end++] & 0x80) {
    }
    return {pos, end - pos};
}

uint64_t varint_at(const std::vector<uint8_t>& file, std::size_t pos) {
    uint64_t v = 0;
    for (int shift = 0;; shift += 7) {
        v |= uint64_t(file[pos] & 0x7F) << shift;
        if (!(file[pos++] & 0x80)) return v;
    }
}

// v as a varint of exactly n bytes (high groups zero where v is small).
std::vector<uint8_t> varint_of(uint64_t v, std::size_t n) {
    std::vector<uint8_t> out;
    for (std::size_t i = 0; i < n; ++i, v >>= 7)
        out.push_back(uint8_t((v & 0x7F) | (i + 1 < n ? 0x80 : 0)));
    return out;
}

// A false packet header (an inter frame 1 from frame 0) claiming `length` payload bytes: 14 bytes.
std::vector<uint8_t> fake_header(uint8_t version, uint32_t length) {
    std::vector<uint8_t> fake = {'R', 'P', 'K', 'T', version, 1, 1, 1, 0, 0};
    const std::vector<uint8_t> l = varint_of(length, 4);
    fake.insert(fake.end(), l.begin(), l.end());
    return fake;
}

}  // namespace

TEST(CodecRecovery, IntactStreamReportsNothing) {
    const Decoded d = decode(make_stream().file);
    EXPECT_TRUE(d.report.ok()) << d.report.summary();
    EXPECT_EQ(d.report.packets, std::size_t(kFrames));
    expect_frames(d, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11});
}

TEST(CodecRecovery, ASinkMayTakeTheFrames) {
    // The sink moves each frame out (as the Python binding does); the decoder must not reuse
    // the moved-from buffers.
    const Stream s = make_stream();
    Decoder decoder;
    StreamInfo info;
    StreamReport report;
    std::vector<Frame> taken;
    ASSERT_TRUE(decode_stream(s.file, decoder, info, report, [&](uint32_t, Frame& f) {
                    taken.push_back(std::move(f));
                    return Status{};
                }).ok());
    Decoded copied = decode(s.file);
    ASSERT_EQ(taken.size(), std::size_t(kFrames));
    for (int i = 0; i < kFrames; ++i)
        EXPECT_TRUE(test::same_bits(taken[i].color, copied.frames.at(uint32_t(i)).color)) << i;
}

TEST(CodecRecovery, TruncatedTailKeepsTheWholePackets) {
    const Stream s = make_stream();
    for (const std::size_t cut : {s.offsets[8] + 10, s.offsets[8] + 100}) {
        std::vector<uint8_t> file(s.file.begin(), s.file.begin() + std::ptrdiff_t(cut));
        const Decoded d = decode(file);
        expect_frames(d, {0, 1, 2, 3, 4, 5, 6, 7});
        ASSERT_EQ(d.report.damage.size(), 1u);
        EXPECT_EQ(d.report.damage[0].offset, s.offsets[8]);
        EXPECT_EQ(d.report.damage[0].bytes, cut - s.offsets[8]);
        ASSERT_EQ(d.report.lost.size(), 1u);
        expect_lost(d.report.lost[0], 8, 0, true, "in the damaged bytes");
        const std::string line = d.report.summary();
        EXPECT_NE(line.find(std::to_string(cut - s.offsets[8]) + " at byte " +
                            std::to_string(s.offsets[8])),
                  std::string::npos)
            << line;
        EXPECT_NE(line.find("frames not decoded: after 7"), std::string::npos) << line;
        // The strict split stops at the damage with the packets before it.
        StreamInfo info;
        std::vector<std::span<const uint8_t>> packets;
        EXPECT_FALSE(split_stream(file, info, packets).ok());
        EXPECT_EQ(packets.size(), 8u);
    }
}

TEST(CodecRecovery, BadLengthInTheMiddleLosesThatFrameAndItsDependants) {
    const Stream s = make_stream();
    const auto [length_at, length_bytes] = length_field(s.file, s.offsets[3]);
    const uint64_t length = varint_at(s.file, length_at);
    for (const int64_t delta : {100, 7, -9}) {  // longer, shorter (the field keeps its size)
        std::vector<uint8_t> file = s.file;
        ASSERT_LT(int64_t(length) + delta, int64_t(1) << (7 * length_bytes)) << delta;
        const std::vector<uint8_t> field =
            varint_of(uint64_t(int64_t(length) + delta), length_bytes);
        std::copy(field.begin(), field.end(), file.begin() + std::ptrdiff_t(length_at));
        const Decoded d = decode(file);
        // Frame 4 is predicted from 3; frame 5 is a key frame.
        expect_frames(d, {0, 1, 2, 5, 6, 7, 8, 9, 10, 11});
        ASSERT_EQ(d.report.damage.size(), 1u) << delta;
        EXPECT_EQ(d.report.damage[0].offset, s.offsets[3]);
        EXPECT_EQ(d.report.damage[0].bytes, s.offsets[4] - s.offsets[3]);
        ASSERT_EQ(d.report.lost.size(), 2u);
        expect_lost(d.report.lost[0], 3, 3, false, "in the damaged bytes");
        expect_lost(d.report.lost[1], 4, 4, false, "reference not decoded");
    }
    // A length past the end of the file: named as such.
    std::vector<uint8_t> file = s.file;
    const std::vector<uint8_t> far = varint_of(1u << 27, 4);
    file.erase(file.begin() + std::ptrdiff_t(length_at),
               file.begin() + std::ptrdiff_t(length_at + length_bytes));
    file.insert(file.begin() + std::ptrdiff_t(length_at), far.begin(), far.end());
    const Decoded d = decode(file);
    expect_frames(d, {0, 1, 2, 5, 6, 7, 8, 9, 10, 11});
    ASSERT_EQ(d.report.damage.size(), 1u);
    EXPECT_NE(d.report.damage[0].reason.find("runs past the end"), std::string::npos)
        << d.report.damage[0].reason;
}

TEST(CodecRecovery, FlippedBitInTheLastPacket) {
    const Stream s = make_stream();
    std::vector<uint8_t> file = s.file;
    file[file.size() - 5] ^= 0x10;
    const Decoded d = decode(file);
    expect_frames(d, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10});
    ASSERT_EQ(d.report.damage.size(), 1u);
    EXPECT_EQ(d.report.damage[0].offset, s.offsets[11]);
    EXPECT_EQ(d.report.damage[0].bytes, s.file.size() - s.offsets[11]);
    EXPECT_NE(d.report.damage[0].reason.find("packet 11: CRC mismatch"), std::string::npos)
        << d.report.damage[0].reason;
    ASSERT_EQ(d.report.lost.size(), 1u);
    expect_lost(d.report.lost[0], 11, 0, true, "in the damaged bytes");
}

TEST(CodecRecovery, FlippedBitInAnInterFrameSkipsToTheNextKeyFrame) {
    const Stream s = make_stream();
    std::vector<uint8_t> file = s.file;
    file[s.offsets[6] + 40] ^= 0x01;
    const Decoded d = decode(file);
    expect_frames(d, {0, 1, 2, 3, 4, 5, 10, 11});
    ASSERT_EQ(d.report.lost.size(), 2u);
    expect_lost(d.report.lost[0], 6, 6, false, "in the damaged bytes");
    expect_lost(d.report.lost[1], 7, 9, false, "reference not decoded");
    const std::string line = d.report.summary();
    EXPECT_NE(
        line.find("frames not decoded: 6 (in the damaged bytes), 7-9 (reference not decoded)"),
        std::string::npos)
        << line;
}

TEST(CodecRecovery, GarbageBetweenPacketsIsSkipped) {
    const Stream s = make_stream();
    std::mt19937 rng(7);
    std::vector<uint8_t> garbage(1000);
    for (uint8_t& b : garbage) b = uint8_t(rng());
    // A false packet header in the garbage, with a length that fits the file.
    const uint8_t version = s.file[s.offsets[0] + 4];
    const std::vector<uint8_t> fake = fake_header(version, 500);
    garbage.insert(garbage.begin() + 100, fake.begin(), fake.end());
    std::vector<uint8_t> file = s.file;
    file.insert(file.begin() + std::ptrdiff_t(s.offsets[7]), garbage.begin(), garbage.end());
    // And some before the first packet and after the last.
    file.insert(file.begin() + std::ptrdiff_t(s.offsets[0]), garbage.begin(), garbage.begin() + 50);
    file.insert(file.end(), garbage.begin() + 100, garbage.begin() + 120);
    const Decoded d = decode(file);
    expect_frames(d, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11});
    ASSERT_EQ(d.report.damage.size(), 3u);
    EXPECT_EQ(d.report.damage[0].offset, s.offsets[0]);
    EXPECT_EQ(d.report.damage[0].bytes, 50u);
    EXPECT_EQ(d.report.damage[1].offset, s.offsets[7] + 50);
    EXPECT_EQ(d.report.damage[1].bytes, garbage.size());
    EXPECT_EQ(d.report.damage[2].bytes, 20u);
    // Nothing is missing between frames 0 and 11; only an open end after the tail's damage.
    ASSERT_EQ(d.report.lost.size(), 1u);
    expect_lost(d.report.lost[0], 12, 0, true, "in the damaged bytes");
}

TEST(CodecRecovery, DamagedFirstKeyFrameLosesFramesUntilTheNextKey) {
    const Stream s = make_stream();
    std::vector<uint8_t> file = s.file;
    file[s.offsets[0] + 50] ^= 0x80;
    const Decoded d = decode(file);
    expect_frames(d, {5, 6, 7, 8, 9, 10, 11});
    ASSERT_EQ(d.report.lost.size(), 2u);
    expect_lost(d.report.lost[0], 0, 0, false, "in the damaged bytes");
    expect_lost(d.report.lost[1], 1, 4, false, "reference not decoded");
}

TEST(CodecRecovery, FalseHeadersCostBoundedWork) {
    // 4 MiB of false packet headers, each claiming a payload that fits: a CRC per candidate
    // would be quadratic; the walk gives up after a few times the file's size.
    const Stream s = make_stream();
    std::vector<uint8_t> file(s.file.begin(), s.file.begin() + 24);
    const uint8_t version = s.file[s.offsets[0] + 4];
    const std::size_t count = (std::size_t(4) << 20) / 32;
    for (std::size_t i = 0; i < count; ++i) {  // 32 bytes each, the rest of the file its payload
        std::vector<uint8_t> fake =
            fake_header(version, uint32_t((count - i - 1) * 32 + 32 - 14 - 4));
        fake.resize(32);
        file.insert(file.end(), fake.begin(), fake.end());
    }
    StreamInfo info;
    std::vector<std::span<const uint8_t>> packets;
    std::vector<StreamDamage> damage;
    ASSERT_TRUE(split_stream(file, info, packets, damage).ok());
    EXPECT_TRUE(packets.empty());
    ASSERT_EQ(damage.size(), 1u);
    EXPECT_EQ(damage[0].bytes, file.size() - 24);
    EXPECT_NE(damage[0].reason.find("gave up"), std::string::npos) << damage[0].reason;
}

TEST(CodecRecovery, BadFileHeaderIsStillAnError) {
    std::vector<uint8_t> file = make_stream().file;
    file[0] = 'X';
    Decoder decoder;
    StreamInfo info;
    StreamReport report;
    const Status s =
        decode_stream(file, decoder, info, report, [](uint32_t, Frame&) { return Status{}; });
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("not a reprise stream"), std::string::npos) << s.message();
}
