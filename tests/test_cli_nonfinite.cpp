// `reprise fruc`, `stereo` and `encode` on frames with NaN, +inf and -inf in ~5 % of every
// channel: exit 0, nothing non-finite written, and one line that counts what was repaired.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <utility>

#include "reprise/core/exr.hpp"
#include "support/cli.hpp"
#include "support/nonfinite.hpp"

using namespace reprise;
namespace fs = std::filesystem;

namespace {

// A spoiled sequence in its own folder, removed with it.
struct Spoiled {
    fs::path dir;
    std::string in;
    NonfiniteCounts counts;
    Spoiled() = default;
    Spoiled(Spoiled&& o) noexcept
        : dir(std::exchange(o.dir, {})), in(std::move(o.in)), counts(o.counts) {}
    Spoiled& operator=(Spoiled&&) = delete;
    ~Spoiled() {
        std::error_code ec;
        if (!dir.empty()) fs::remove_all(dir, ec);
    }
};

Spoiled write_spoiled(const std::string& name, int frames) {
    Spoiled s;
    s.dir = test::fresh_directory(fs::temp_directory_path() /
                                  ("reprise_cli_nonfinite_" + name + std::to_string(::getpid())));
    s.in = (s.dir / "in").string();
    fs::create_directories(s.in);
    std::vector<Frame> in = test::spoiled_sequence(frames, s.counts);
    for (int i = 0; i < frames; ++i) EXPECT_TRUE(write_frame(frame_path(s.in, i), in[i]).ok());
    return s;
}

std::string count_line(const NonfiniteCounts& c, int frames) {
    return std::to_string(c.total()) + " non-finite values (colour " + std::to_string(c.color) +
           ", depth " + std::to_string(c.depth) + ", motion " + std::to_string(c.motion) + ") in " +
           std::to_string(frames) + " frames";
}

// Frames in `dir` and the non-finite values in them (+inf depth is background).
std::size_t nonfinite_written(const fs::path& dir, int& frames) {
    std::size_t n = 0;
    frames = 0;
    for (const auto& entry : fs::directory_iterator(dir)) {
        if (entry.path().extension() != ".exr") continue;
        Frame f;
        EXPECT_TRUE(read_frame(entry.path().string(), f).ok()) << entry.path();
        n += test::nonfinite_in(f);
        ++frames;
    }
    return n;
}

std::size_t occurrences(const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
}

}  // namespace

TEST(CliNonfinite, FrucRepairsCountsOnceAndWritesFiniteFrames) {
    const Spoiled s = write_spoiled("fruc", 4);
    for (const std::string warp : {"grid", "reverse", "splat"}) {
        const std::string out = (s.dir / ("out-" + warp)).string();
        const test::Outcome r = test::run_reprise(
            "fruc --in " + s.in + " --factor 2 --warp " + warp + " --out " + out, 120);
        ASSERT_EQ(r.status, 0) << r.output;
        EXPECT_EQ(occurrences(r.output, "[fruc] input: " + count_line(s.counts, 4)), 1u)
            << r.output;
        int frames = 0;
        EXPECT_EQ(nonfinite_written(out, frames), 0u) << warp;
        EXPECT_EQ(frames, 7);
    }
}

TEST(CliNonfinite, StereoAndEncodeRepairAndCount) {
    const Spoiled s = write_spoiled("stereo", 2);
    const std::string out = (s.dir / "eyes").string();
    test::Outcome r = test::run_reprise("stereo --in " + s.in + " --out " + out, 120);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(occurrences(r.output, "[stereo] input: " + count_line(s.counts, 2)), 1u) << r.output;
    int frames = 0;
    EXPECT_EQ(nonfinite_written(fs::path(out) / "left", frames), 0u);
    EXPECT_EQ(frames, 2);
    EXPECT_EQ(nonfinite_written(fs::path(out) / "right", frames), 0u);
    EXPECT_EQ(frames, 2);

    const std::string stream = (s.dir / "x.rps").string(), back = (s.dir / "back").string();
    r = test::run_reprise("encode --in " + s.in + " --out " + stream, 120);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(occurrences(r.output, "[encode] input: " + count_line(s.counts, 2)), 1u) << r.output;
    r = test::run_reprise("decode " + stream + " --out " + back, 120);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(nonfinite_written(back, frames), 0u);
    EXPECT_EQ(frames, 2);
}
