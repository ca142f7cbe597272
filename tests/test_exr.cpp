// EXR frames and sequences: bit-exact round trip, bad files, Blender import, sequences.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <iterator>
#include <limits>
#include <random>

#include "reprise/core/exr.hpp"
#include "support/cli.hpp"
#include "support/frames.hpp"

namespace fs = std::filesystem;
using namespace reprise;

namespace {

class ExrTest : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = test::fresh_directory(
            fs::temp_directory_path() /
            ("reprise_exr_" + std::to_string(::getpid()) + "_" + info->name()));
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }

    fs::path dir_;
};

float random_bits(std::mt19937& rng) {
    const uint32_t bits = rng();
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
}

using test::same_bits;

bool same_bits(const glm::mat4& a, const glm::mat4& b) {
    return std::memcmp(&a, &b, sizeof a) == 0;
}

Frame full_frame(int width, int height, uint32_t seed) {
    std::mt19937 rng(seed);
    Frame f;
    f.color.resize(width, height);
    f.depth.resize(width, height);
    f.motion.resize(width, height);
    f.normal.resize(width, height);
    f.id.resize(width, height);
    for (std::size_t i = 0; i < f.color.pixel_count(); ++i) {
        // Any 32-bit pattern: NaNs with payloads, infinities, denormals.
        f.color.data()[i] = {random_bits(rng), random_bits(rng), random_bits(rng),
                             random_bits(rng)};
        f.depth.data()[i] = i % 7 == 0 ? std::numeric_limits<float>::infinity() : random_bits(rng);
        f.motion.data()[i] = {random_bits(rng), random_bits(rng)};
        f.normal.data()[i] = {random_bits(rng), random_bits(rng), random_bits(rng)};
        f.id.data()[i] = i % 5 == 0 ? std::numeric_limits<uint32_t>::max() : rng();
    }
    Camera& c = f.camera;
    c.view = glm::lookAt(glm::vec3(1.5f, 2.0f, 7.0f), glm::vec3(0.1f, 0.2f, 0.0f),
                         glm::vec3(0.0f, 1.0f, 0.0f));
    c.projection = glm::perspective(0.9f, float(width) / float(height), 0.05f, 500.0f);
    c.prev_view = glm::translate(c.view, glm::vec3(0.1f, -0.2f, 0.3f));
    c.prev_projection = glm::perspective(0.91f, float(width) / float(height), 0.05f, 500.0f);
    c.near = 0.05f;
    c.far = 500.0f;
    c.jitter = {0.3125f, -0.1f};
    c.time = 1.0 / 3.0;
    f.fps = 29.97;
    return f;
}

void write_raw(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
}

// Writes an EXR with OIIO directly: channel names, float data, optional spec changes.
void write_exr(const std::string& path, int width, int height,
               const std::vector<std::string>& channels, const std::vector<float>& pixels) {
    OIIO::ImageSpec spec(width, height, int(channels.size()), OIIO::TypeFloat);
    spec.channelnames = channels;
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out && out->open(path, spec)) << OIIO::geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeFloat, pixels.data()));
    ASSERT_TRUE(out->close());
}

}  // namespace

TEST_F(ExrTest, RoundTripIsBitExact) {
    const Frame written = full_frame(37, 23, 1);
    ASSERT_TRUE(write_frame(path("a.exr"), written).ok());
    Frame read;
    const Status s = read_frame(path("a.exr"), read);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_TRUE(same_bits(read.color, written.color));
    EXPECT_TRUE(same_bits(read.depth, written.depth));
    EXPECT_TRUE(same_bits(read.motion, written.motion));
    EXPECT_TRUE(same_bits(read.normal, written.normal));
    EXPECT_TRUE(same_bits(read.id, written.id));
    EXPECT_TRUE(same_bits(read.camera.view, written.camera.view));
    EXPECT_TRUE(same_bits(read.camera.projection, written.camera.projection));
    EXPECT_TRUE(same_bits(read.camera.prev_view, written.camera.prev_view));
    EXPECT_TRUE(same_bits(read.camera.prev_projection, written.camera.prev_projection));
    EXPECT_EQ(read.camera.near, written.camera.near);
    EXPECT_EQ(read.camera.far, written.camera.far);
    EXPECT_EQ(read.camera.jitter, written.camera.jitter);
    EXPECT_EQ(read.camera.time, written.camera.time);
    EXPECT_EQ(read.fps, written.fps);
}

TEST_F(ExrTest, TheCutFlagRoundTripsAndIsUnknownWhenAbsent) {
    for (const Cut cut : {Cut::Yes, Cut::No, Cut::Unknown}) {
        Frame written = full_frame(9, 5, 1);
        written.camera.cut = cut;
        ASSERT_TRUE(write_frame(path("cut.exr"), written).ok());
        Frame read;
        ASSERT_TRUE(read_frame(path("cut.exr"), read).ok());
        EXPECT_EQ(read.camera.cut, cut) << int(cut);
    }
}

TEST_F(ExrTest, LargerThanOneStripRoundTrips) {
    Frame written = full_frame(130, 150, 2);
    ASSERT_TRUE(write_frame(path("big.exr"), written).ok());
    Frame read;
    ASSERT_TRUE(read_frame(path("big.exr"), read).ok());
    EXPECT_TRUE(same_bits(read.color, written.color));
    EXPECT_TRUE(same_bits(read.id, written.id));
}

TEST_F(ExrTest, OneByOne) {
    Frame written = full_frame(1, 1, 3);
    ASSERT_TRUE(write_frame(path("one.exr"), written).ok());
    Frame read;
    ASSERT_TRUE(read_frame(path("one.exr"), read).ok());
    EXPECT_TRUE(same_bits(read.color, written.color));
    EXPECT_TRUE(same_bits(read.normal, written.normal));
}

// Row vector times a row-major Imath matrix, as OpenEXR's multVecMatrix does (without the divide).
glm::vec4 times(const glm::vec4& p, const float (&m)[16]) {
    glm::vec4 out(0.0f);
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) out[j] += p[i] * m[4 * i + j];
    return out;
}

// OpenEXR's standard: worldToCamera goes to a camera space with +z forward; worldToNDC puts the
// image's top-left corner at (0, 0) and its bottom-right corner at (1, 1).
TEST_F(ExrTest, StandardMatricesFollowOpenExr) {
    Frame f = full_frame(8, 6, 4);
    ASSERT_TRUE(write_frame(path("m.exr"), f).ok());
    auto in = OIIO::ImageInput::open(path("m.exr"));
    ASSERT_TRUE(in);
    const glm::vec4 world(0.4f, 0.4f, 0.0f, 1.0f);  // near the point the camera looks at
    const glm::vec4 eye = f.camera.view * world;

    float m[16];
    ASSERT_TRUE(in->spec().getattribute("worldToCamera", OIIO::TypeMatrix44, m));
    const glm::vec4 camera = times(world, m);
    EXPECT_GT(camera.z, 0.0f);
    EXPECT_FLOAT_EQ(camera.x, eye.x);
    EXPECT_FLOAT_EQ(camera.y, eye.y);
    EXPECT_FLOAT_EQ(camera.z, -eye.z);

    ASSERT_TRUE(in->spec().getattribute("worldToNDC", OIIO::TypeMatrix44, m));
    const glm::vec4 ndc = times(world, m);
    const glm::vec4 clip = f.camera.projection * eye;
    EXPECT_NEAR(ndc.x / ndc.w, 0.5f + 0.5f * clip.x / clip.w, 1e-5f);
    EXPECT_NEAR(ndc.y / ndc.w, 0.5f - 0.5f * clip.y / clip.w, 1e-5f);
    // The point is right of and above the image centre.
    EXPECT_GT(ndc.x / ndc.w, 0.5f);
    EXPECT_LT(ndc.y / ndc.w, 0.5f);
    in->close();
}

// A file from another program has worldToCamera and worldToNDC but no reprise:* attributes.
TEST_F(ExrTest, ProjectionFromStandardMatrices) {
    const Frame f = full_frame(8, 6, 15);
    OIIO::ImageSpec spec(2, 2, 3, OIIO::TypeFloat);
    const glm::mat4 to_camera = exr_world_to_camera(f.camera.view);
    const glm::mat4 to_ndc = exr_world_to_ndc(f.camera.projection, f.camera.view);
    spec.attribute("worldToCamera", OIIO::TypeMatrix44, &to_camera);
    spec.attribute("worldToNDC", OIIO::TypeMatrix44, &to_ndc);
    auto out = OIIO::ImageOutput::create(path("other.exr"));
    ASSERT_TRUE(out->open(path("other.exr"), spec));
    const std::vector<float> pixels(12, 0.5f);
    ASSERT_TRUE(out->write_image(OIIO::TypeFloat, pixels.data()));
    ASSERT_TRUE(out->close());
    Frame read;
    ASSERT_TRUE(read_frame(path("other.exr"), read).ok());
    EXPECT_TRUE(same_bits(read.camera.view, f.camera.view));
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            EXPECT_NEAR(read.camera.projection[c][r], f.camera.projection[c][r], 1e-4f);
    EXPECT_TRUE(same_bits(read.camera.prev_view, f.camera.view));
}

TEST_F(ExrTest, AbsentBuffersAreLeftOut) {
    Frame written = full_frame(9, 5, 5);
    written.motion.clear();
    written.normal.clear();
    written.id.clear();
    ASSERT_TRUE(write_frame(path("part.exr"), written).ok());
    FrameHeader header;
    ASSERT_TRUE(read_frame_header(path("part.exr"), header).ok());
    EXPECT_EQ(header.channels.size(), 5u);  // R G B A Z
    Frame read = full_frame(3, 3, 6);       // stale buffers must go
    ASSERT_TRUE(read_frame(path("part.exr"), read).ok());
    EXPECT_TRUE(same_bits(read.color, written.color));
    EXPECT_TRUE(same_bits(read.depth, written.depth));
    EXPECT_TRUE(read.motion.empty());
    EXPECT_TRUE(read.normal.empty());
    EXPECT_TRUE(read.id.empty());
}

TEST_F(ExrTest, MissingAlphaIsOneAndMissingCameraIsDefault) {
    write_exr(path("rgb.exr"), 2, 1, {"R", "G", "B"}, {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f});
    Frame f;
    const Status s = read_frame(path("rgb.exr"), f);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_EQ(f.color(1, 0), glm::vec4(0.4f, 0.5f, 0.6f, 1.0f));
    EXPECT_TRUE(f.depth.empty());
    EXPECT_EQ(f.camera.view, glm::mat4(1.0f));
    EXPECT_EQ(f.fps, 0.0);
    FrameHeader header;
    ASSERT_TRUE(read_frame_header(path("rgb.exr"), header).ok());
    EXPECT_FALSE(header.has_camera);
    EXPECT_FALSE(header.blender);
}

TEST_F(ExrTest, HalfChannelsAreConverted) {
    OIIO::ImageSpec spec(2, 1, 4, OIIO::TypeHalf);
    spec.channelnames = {"R", "G", "B", "Z"};
    const float pixels[] = {0.5f, 1.0f, 2.0f, 3.0f, -1.0f, 65504.0f, 0.25f, INFINITY};
    auto out = OIIO::ImageOutput::create(path("half.exr"));
    ASSERT_TRUE(out->open(path("half.exr"), spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeFloat, pixels));
    ASSERT_TRUE(out->close());
    Frame f;
    ASSERT_TRUE(read_frame(path("half.exr"), f).ok());
    EXPECT_EQ(f.color(1, 0), glm::vec4(-1.0f, 65504.0f, 0.25f, 1.0f));
    EXPECT_EQ(f.depth(0, 0), 3.0f);
    EXPECT_EQ(f.depth(1, 0), INFINITY);
}

TEST_F(ExrTest, TiledFilesAreRead) {
    OIIO::ImageSpec spec(70, 40, 3, OIIO::TypeFloat);
    spec.tile_width = spec.tile_height = 16;
    std::vector<float> pixels(70 * 40 * 3);
    for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = float(i);
    auto out = OIIO::ImageOutput::create(path("tiled.exr"));
    ASSERT_TRUE(out->open(path("tiled.exr"), spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeFloat, pixels.data()));
    ASSERT_TRUE(out->close());
    Frame f;
    const Status s = read_frame(path("tiled.exr"), f);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_EQ(f.color(69, 39), glm::vec4(pixels[(39 * 70 + 69) * 3], pixels[(39 * 70 + 69) * 3 + 1],
                                         pixels[(39 * 70 + 69) * 3 + 2], 1.0f));
}

TEST_F(ExrTest, WriteChecksItsInput) {
    Frame f;
    EXPECT_FALSE(write_frame(path("empty.exr"), f).ok());
    f = full_frame(4, 4, 7);
    f.depth.resize(4, 3);
    const Status s = write_frame(path("mismatch.exr"), f);
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.message().find("depth"), std::string::npos) << s.message();
    EXPECT_FALSE(fs::exists(path("mismatch.exr")));
    f.depth.clear();
    EXPECT_FALSE(write_frame(path("no/such/folder/x.exr"), f).ok());
}

TEST_F(ExrTest, FailedWriteLeavesNoFile) {
    // The target is a folder: the rename fails, and the temporary file must be gone.
    fs::create_directories(path("taken.exr"));
    const Frame f = full_frame(4, 4, 8);
    EXPECT_FALSE(write_frame(path("taken.exr"), f).ok());
    int files = 0;
    for (const auto& entry : fs::directory_iterator(dir_)) files += entry.is_regular_file();
    EXPECT_EQ(files, 0);
}

TEST_F(ExrTest, OverwriteReplacesTheFrame) {
    ASSERT_TRUE(write_frame(path("f.exr"), full_frame(5, 5, 9)).ok());
    const Frame second = full_frame(6, 4, 10);
    ASSERT_TRUE(write_frame(path("f.exr"), second).ok());
    Frame read;
    ASSERT_TRUE(read_frame(path("f.exr"), read).ok());
    EXPECT_TRUE(same_bits(read.color, second.color));
}

void expect_error_naming(const Status& s, const std::string& file) {
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.message().find(file), std::string::npos) << s.message();
}

TEST_F(ExrTest, MissingFileIsAnError) {
    Frame f;
    expect_error_naming(read_frame(path("nothing.exr"), f), "nothing.exr");
    expect_error_naming(read_frame(dir_.string(), f), dir_.string());
}

TEST_F(ExrTest, TruncatedFileIsAnError) {
    ASSERT_TRUE(write_frame(path("t.exr"), full_frame(64, 48, 11)).ok());
    const auto size = fs::file_size(path("t.exr"));
    fs::resize_file(path("t.exr"), size / 2);
    Frame f;
    expect_error_naming(read_frame(path("t.exr"), f), "t.exr");
    fs::resize_file(path("t.exr"), 100);  // inside the header
    expect_error_naming(read_frame(path("t.exr"), f), "t.exr");
}

TEST_F(ExrTest, GarbageAndEmptyFilesAreErrors) {
    std::mt19937 rng(12);
    std::string garbage(4096, '\0');
    for (char& c : garbage) c = char(rng());
    write_raw(path("garbage.exr"), garbage);
    write_raw(path("empty.exr"), "");
    // The EXR magic number followed by garbage.
    write_raw(path("magic.exr"), std::string("\x76\x2f\x31\x01\x02\0\0\0", 8) + garbage);
    Frame f;
    expect_error_naming(read_frame(path("garbage.exr"), f), "garbage.exr");
    expect_error_naming(read_frame(path("empty.exr"), f), "empty.exr");
    expect_error_naming(read_frame(path("magic.exr"), f), "magic.exr");
}

// Found by fuzz_exr: OpenEXR allocates an attribute at its declared size before reading it, so a
// 556-byte file asking for a 1.8 GB "Software" string took 1.9 GB and seconds per open; and it
// sizes buffers by the data window before reprise's size check (899 bytes without a dataWindow
// came out 2818056 pixels wide and took 134 MB); a type name past OpenEXR's 31-byte limit put
// the size field elsewhere for OpenEXR than for the check (1.7 GB); a 4x4 image in one 8192x8192
// tile took 1.4 GB and 19 s (CI's fuzz run, 2 GB limit).
// A real frame whose dataWindow is patched to claim 16384x16384: the frame's buffers would take
// 11 GiB, refused from the header by the memory limit (4 GiB by default) before pixels are read.
TEST_F(ExrTest, AFrameBeyondTheMemoryLimitIsRefusedFromItsHeader) {
    // Large enough that OpenEXR finds its table of 16384 rows' offsets inside the file.
    ASSERT_TRUE(write_frame(path("small.exr"), full_frame(64, 48, 2)).ok());
    std::string bytes = test::read_text(path("small.exr"));
    const std::string key("dataWindow\0box2i\0", 17);
    const std::size_t at = bytes.find(key);
    ASSERT_NE(at, std::string::npos);
    const int32_t box[4] = {0, 0, 16383, 16383};
    bytes.replace(at + key.size() + 4, sizeof box, reinterpret_cast<const char*>(box), sizeof box);
    write_raw(path("claims.exr"), bytes);
    Frame f;
    const Status s = read_frame(path("claims.exr"), f);
    ASSERT_FALSE(s.ok());
    for (const char* word : {"claims.exr", "16384x16384", "needs 11 GiB; limit 4 GiB"})
        EXPECT_NE(s.message().find(word), std::string::npos) << word << ": " << s.message();
    EXPECT_TRUE(f.color.empty());
    Sequence sequence;
    ASSERT_TRUE(open_sequence(path("claims.exr"), sequence).ok());
    EXPECT_NE(read_frame(sequence, 0, f).message().find("needs"), std::string::npos);
}

TEST_F(ExrTest, HeadersAskingForHugeAllocationsAreRefused) {
    auto attribute = [](const std::string& name, const std::string& type, int32_t size) {
        std::string bytes = name + '\0' + type + '\0';
        bytes.append(reinterpret_cast<const char*>(&size), 4);
        return bytes;
    };
    auto data_window = [&](int32_t width, int32_t height) {
        const int32_t box[4] = {0, 0, width - 1, height - 1};
        return attribute("dataWindow", "box2i", 16) +
               std::string(reinterpret_cast<const char*>(box), 16);
    };
    const std::string magic("\x76\x2f\x31\x01\x02\0\0\0", 8);
    const std::string multipart("\x76\x2f\x31\x01\x02\x10\0\0", 8);
    const std::string end(1, '\0');
    const std::vector<std::pair<std::string, std::string>> files = {
        {"huge.exr",
         magic + data_window(4, 4) + attribute("Software", "string", 1828716733) + "oiio"},
        {"negative.exr", magic + attribute("owner", "string", -5) + "x"},
        {"parts.exr", multipart + data_window(4, 4) + end + data_window(4, 4) +
                          attribute("name", "string", 1 << 30) + "b"},
        {"no-window.exr", magic + attribute("capDate", "string", 1) + "x" + end + "pixels"},
        {"no-window-part.exr",
         multipart + data_window(4, 4) + end + attribute("name", "string", 1) + "b" + end + end},
        {"wide.exr", magic + data_window(1 << 30, 6) + end + "pixels"},
        {"long-type.exr", magic + data_window(4, 4) +
                              attribute("Software", "string" + std::string(40, 'x'), 4) + "oiio" +
                              end},
        {"inverted.exr", magic + data_window(-3, 6) + end + "pixels"},
        {"tiles.exr", magic + data_window(4, 4) + attribute("tiles", "tiledesc", 9) +
                          std::string("\0\x20\0\0\0\x20\0\0\0", 9) + end + "pixels"},

        // OpenEXR reads a matrix at its own 64 bytes and goes on from there: the 16 declared here
        // would put the next "attribute" inside this one (a fuzzer's 1.7 GB string, 3 KB file).
        {"short-matrix.exr", magic + data_window(4, 4) + attribute("m", "m44f", 16) +
                                 std::string(16, '\0') + end + "pixels"},
        {"preview.exr", magic + data_window(4, 4) + attribute("preview", "preview", 12) +
                            std::string("\xff\xff\0\0\xff\xff\0\0\0\0\0\0", 12) + end + "pixels"},
        {"strings.exr", magic + data_window(4, 4) + attribute("multiView", "stringvector", 8) +
                            std::string("\0\0\0\x70rose", 8) + end + "pixels"},
    };
    FrameHeader header;
    Frame f;
    for (const auto& [name, bytes] : files) {
        write_raw(path(name), bytes);
        const Status s = read_frame_header(path(name), header);
        expect_error_naming(s, name);
        EXPECT_NE(s.message().find("(header: "), std::string::npos) << s.message();
        expect_error_naming(read_frame(path(name), f), name);
    }
    // Real frames pass the same walk (so does every other file read in this suite).
    ASSERT_TRUE(write_frame(path("ok.exr"), full_frame(5, 4, 2)).ok());
    ASSERT_TRUE(read_frame(path("ok.exr"), f).ok());
    // So do tiles of OpenEXR's usual 64 pixels on an image smaller than one tile.
    OIIO::ImageSpec spec(5, 4, 4, OIIO::TypeFloat);
    spec.tile_width = spec.tile_height = 64;
    const std::vector<float> pixels(5 * 4 * 4, 0.25f);
    auto out = OIIO::ImageOutput::create("openexr");
    ASSERT_TRUE(out->open(path("tiled.exr"), spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeFloat, pixels.data()));
    ASSERT_TRUE(out->close());
    ASSERT_TRUE(read_frame(path("tiled.exr"), f).ok());
    EXPECT_EQ(f.color(4, 3).x, 0.25f);
}

// Property: a damaged frame is read or refused, never a crash (run under ASan in CI).
TEST_F(ExrTest, DamagedFilesAreReadOrRefused) {
    ASSERT_TRUE(write_frame(path("good.exr"), full_frame(24, 20, 16)).ok());
    std::ifstream in(path("good.exr"), std::ios::binary);
    const std::string good((std::istreambuf_iterator<char>(in)), {});
    std::mt19937 rng(17);
    int refused = 0;
    for (int trial = 0; trial < 200; ++trial) {
        std::string bytes = good;
        for (int k = 1 + int(rng() % 8); k > 0; --k) bytes[rng() % bytes.size()] = char(rng());
        if (trial % 4 == 0) bytes.resize(rng() % bytes.size());
        write_raw(path("damaged.exr"), bytes);
        Frame f;
        const Status s = read_frame(path("damaged.exr"), f);
        if (!s.ok()) {
            ++refused;
            EXPECT_NE(s.message().find("damaged.exr"), std::string::npos) << s.message();
        }
    }
    EXPECT_GT(refused, 0);
}

TEST_F(ExrTest, ImagesOfOtherFormatsAreRejected) {
    OIIO::ImageSpec spec(4, 4, 3, OIIO::TypeUInt8);
    std::vector<unsigned char> pixels(48, 128);
    auto out = OIIO::ImageOutput::create("png");
    ASSERT_TRUE(out->open(path("image.png"), spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeUInt8, pixels.data()));
    ASSERT_TRUE(out->close());
    fs::rename(path("image.png"), path("png.exr"));
    Frame f;
    expect_error_naming(read_frame(path("png.exr"), f), "png.exr");
}

TEST_F(ExrTest, OversizedHeaderIsRejectedBeforeAllocating) {
    // 20000x10: over kMaxImageSide; write it line by line to keep the test light.
    OIIO::ImageSpec spec(20000, 10, 3, OIIO::TypeHalf);
    auto out = OIIO::ImageOutput::create(path("wide.exr"));
    ASSERT_TRUE(out->open(path("wide.exr"), spec));
    std::vector<float> line(20000 * 3, 0.5f);
    for (int y = 0; y < 10; ++y)
        ASSERT_TRUE(out->write_scanline(y, 0, OIIO::TypeFloat, line.data()));
    ASSERT_TRUE(out->close());
    Frame f;
    const Status s = read_frame(path("wide.exr"), f);
    expect_error_naming(s, "wide.exr");
    EXPECT_NE(s.message().find("20000x10"), std::string::npos) << s.message();
    EXPECT_TRUE(f.color.empty());
}

TEST_F(ExrTest, MissingColorChannelIsAnError) {
    write_exr(path("gb.exr"), 1, 1, {"G", "B", "Z"}, {1.0f, 2.0f, 3.0f});
    Frame f;
    const Status s = read_frame(path("gb.exr"), f);
    expect_error_naming(s, "gb.exr");
    EXPECT_NE(s.message().find("channel R"), std::string::npos) << s.message();
}

TEST_F(ExrTest, HalfAMotionPairIsAnError) {
    write_exr(path("mx.exr"), 1, 1, {"R", "G", "B", "motion.x"}, {1.0f, 2.0f, 3.0f, 4.0f});
    Frame f;
    const Status s = read_frame(path("mx.exr"), f);
    expect_error_naming(s, "mx.exr");
    EXPECT_NE(s.message().find("motion.y"), std::string::npos) << s.message();
}

// A file laid out the way Blender writes a multilayer render: LAYER.PASS.CHANNEL names, rows
// top to bottom, Cycles' 1e10 background depth and the Vector pass in pixels with +y up:
// (X, Y) = previous position - current position, (Z, W) = current - next.
TEST_F(ExrTest, BlenderMultilayerImport) {
    const int width = 3, height = 2;
    const std::vector<std::string> channels = {
        "Composite.Combined.R", "Composite.Combined.G", "Composite.Combined.B",
        "ViewLayer.Combined.A", "ViewLayer.Combined.B", "ViewLayer.Combined.G",
        "ViewLayer.Combined.R", "ViewLayer.Depth.Z",    "ViewLayer.IndexOB.X",
        "ViewLayer.Normal.X",   "ViewLayer.Normal.Y",   "ViewLayer.Normal.Z",
        "ViewLayer.Vector.W",   "ViewLayer.Vector.X",   "ViewLayer.Vector.Y",
        "ViewLayer.Vector.Z"};
    const int n = int(channels.size());
    std::vector<float> pixels(std::size_t(width) * height * n, 0.0f);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            float* p = &pixels[(std::size_t(y) * width + x) * n];
            p[0] = p[1] = p[2] = 9.0f;  // Composite: must not be chosen
            p[3] = 1.0f;
            p[4] = 0.3f;
            p[5] = 0.2f;
            p[6] = float(x) + 10.0f * float(y);
            p[7] = (x == 2) ? 1e10f : 4.5f;
            p[8] = (x == 2) ? 0.0f : 7.0f;
            p[9] = 0.0f;
            p[10] = 0.0f;
            p[11] = 1.0f;
            // The surface was 2 px to the left and 1 px lower on screen in the previous frame:
            // Blender's +y is up, so lower is -1.
            p[13] = -2.0f;
            p[14] = -1.0f;
            p[15] = -2.0f;
            p[12] = -1.0f;
        }
    write_exr(path("0001.exr"), width, height, channels, pixels);

    FrameHeader header;
    ASSERT_TRUE(read_frame_header(path("0001.exr"), header).ok());
    EXPECT_TRUE(header.blender);
    Frame f;
    const Status s = read_frame(path("0001.exr"), f);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(f.width(), width);
    ASSERT_EQ(f.height(), height);
    EXPECT_EQ(f.color(1, 1), glm::vec4(11.0f, 0.2f, 0.3f, 1.0f));  // top row stays on top
    EXPECT_EQ(f.depth(0, 0), 4.5f);
    EXPECT_EQ(f.depth(2, 1), std::numeric_limits<float>::infinity());
    // reprise: p + motion = previous position, +y down: 2 px left, 1 px down.
    EXPECT_EQ(f.motion(1, 0), glm::vec2(-2.0f, 1.0f));
    EXPECT_EQ(f.normal(0, 0), glm::vec3(0.0f, 0.0f, 1.0f));
    EXPECT_EQ(f.id(0, 0), 7u);
    EXPECT_EQ(f.id(2, 0), 0u);
}

TEST_F(ExrTest, BlenderWithoutOptionalPassesAndWithAView) {
    write_exr(path("v.exr"), 1, 1,
              {"RenderLayer.Combined.left.R", "RenderLayer.Combined.left.G",
               "RenderLayer.Combined.left.B"},
              {0.25f, 0.5f, 0.75f});
    Frame f;
    const Status s = read_frame(path("v.exr"), f);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_EQ(f.color(0, 0), glm::vec4(0.25f, 0.5f, 0.75f, 1.0f));
    EXPECT_TRUE(f.depth.empty());
    EXPECT_TRUE(f.motion.empty());
}

TEST_F(ExrTest, BlenderLayoutWritesBlenderNamesAndReadsBack) {
    Frame written = full_frame(9, 7, 4);
    // Values the layout converts: finite depth and motion, ids a float holds exactly.
    for (std::size_t i = 0; i < written.color.pixel_count(); ++i) {
        written.depth.data()[i] = i % 7 == 0 ? std::numeric_limits<float>::infinity() : 0.5f + i;
        written.motion.data()[i] = {0.25f * float(i), -1.5f + float(i % 3)};
        written.id.data()[i] = uint32_t(i % 11);
    }
    ASSERT_TRUE(write_frame(path("b.exr"), written, {.layout = ExrLayout::Blender}).ok());
    FrameHeader header;
    ASSERT_TRUE(read_frame_header(path("b.exr"), header).ok());
    EXPECT_TRUE(header.blender);
    const std::vector<std::string> expected = {
        "ViewLayer.Combined.R", "ViewLayer.Combined.A", "ViewLayer.Depth.Z",  "ViewLayer.Vector.X",
        "ViewLayer.Vector.W",   "ViewLayer.Normal.Z",   "ViewLayer.IndexOB.X"};
    for (const std::string& name : expected)
        EXPECT_NE(std::find(header.channels.begin(), header.channels.end(), name),
                  header.channels.end())
            << name;
    for (const char* name : {"R", "Z", "motion.x", "N.X", "id"})
        EXPECT_EQ(std::find(header.channels.begin(), header.channels.end(), name),
                  header.channels.end())
            << name;

    // Blender's conventions in the file: background depth 1e10, vector +y up.
    auto in = OIIO::ImageInput::open(path("b.exr"));
    ASSERT_TRUE(in);
    const OIIO::ImageSpec& spec = in->spec();
    std::vector<float> pixels(std::size_t(spec.width) * spec.height * spec.nchannels);
    ASSERT_TRUE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeFloat, pixels.data()));
    const int z = spec.channelindex("ViewLayer.Depth.Z"),
              vy = spec.channelindex("ViewLayer.Vector.Y");
    EXPECT_EQ(pixels[z], 1e10f);
    EXPECT_EQ(pixels[spec.nchannels + vy], -written.motion.data()[1].y);

    Frame read;
    const Status s = read_frame(path("b.exr"), read);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_TRUE(same_bits(read.color, written.color));
    EXPECT_TRUE(same_bits(read.depth, written.depth));
    EXPECT_TRUE(same_bits(read.motion, written.motion));
    EXPECT_TRUE(same_bits(read.normal, written.normal));
    EXPECT_TRUE(same_bits(read.id, written.id));
    EXPECT_TRUE(same_bits(read.camera.view, written.camera.view));
    EXPECT_EQ(read.fps, written.fps);
}

TEST_F(ExrTest, SequenceIsSortedWithFps) {
    Frame f = full_frame(4, 3, 13);
    f.fps = 24.0;
    for (int i : {10, 2, 0, 1, 9}) ASSERT_TRUE(write_frame(frame_path(dir_.string(), i), f).ok());
    write_raw(path("notes.txt"), "not a frame");
    Sequence seq;
    const Status s = open_sequence(dir_.string(), seq);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(seq.files.size(), 5u);
    EXPECT_EQ(seq.files[0], frame_path(dir_.string(), 0));
    EXPECT_EQ(seq.files[3], frame_path(dir_.string(), 9));
    EXPECT_EQ(seq.files[4], frame_path(dir_.string(), 10));
    EXPECT_EQ(seq.fps, 24.0);

    Sequence one;
    ASSERT_TRUE(open_sequence(seq.files[2], one).ok());
    ASSERT_EQ(one.files.size(), 1u);
    EXPECT_EQ(one.fps, 24.0);
}

TEST_F(ExrTest, BlenderNamesSortNumerically) {
    write_exr(path("9.exr"), 1, 1, {"R", "G", "B"}, {0, 0, 0});
    write_exr(path("10.exr"), 1, 1, {"R", "G", "B"}, {0, 0, 0});
    write_exr(path("0008.exr"), 1, 1, {"R", "G", "B"}, {0, 0, 0});
    Sequence seq;
    ASSERT_TRUE(open_sequence(dir_.string(), seq).ok());
    ASSERT_EQ(seq.files.size(), 3u);
    EXPECT_EQ(fs::path(seq.files[0]).filename(), "0008.exr");
    EXPECT_EQ(fs::path(seq.files[1]).filename(), "9.exr");
    EXPECT_EQ(fs::path(seq.files[2]).filename(), "10.exr");
    EXPECT_EQ(seq.fps, 0.0);
}

TEST_F(ExrTest, EmptyOrMissingSequenceIsAnError) {
    Sequence seq;
    expect_error_naming(open_sequence(dir_.string(), seq), dir_.string());
    expect_error_naming(open_sequence(path("missing"), seq), "missing");
}

TEST(ExrFramePath, Format) {
    EXPECT_EQ(frame_path("out", 42), "out/frame_00042.exr");
    EXPECT_EQ(frame_path("out/", 0), "out/frame_00000.exr");
}
