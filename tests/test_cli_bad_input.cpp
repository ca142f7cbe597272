// The `reprise` executable on bad input: one clear message, exit status 1 or 2, never a crash
// or a hang. Also walks every glTF file of Debian's assimp-testmodels through `reprise render`.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "support/cli.hpp"

namespace fs = std::filesystem;
using reprise::test::fresh_directory;
using reprise::test::Outcome;

namespace {

Outcome run(const std::string& arguments) { return reprise::test::run_reprise(arguments, 120); }

fs::path scratch(const std::string& name) {
    return fresh_directory(fs::temp_directory_path() / ("reprise-cli-" + name));
}

void expect_clean_failure(const Outcome& r, const std::string& must_mention,
                          const std::string& what) {
    EXPECT_TRUE(r.status == 1 || r.status == 2) << what << ": status " << r.status << "\n"
                                                << r.output;
    EXPECT_NE(r.output.find(must_mention), std::string::npos) << what << ":\n" << r.output;
    EXPECT_EQ(r.output.find("Sanitizer"), std::string::npos) << what << ":\n" << r.output;
}

}  // namespace

TEST(CliBadInput, ArgumentsGetOneMessageAndStatusTwo) {
    fs::path out = scratch("args");
    expect_clean_failure(run(""), "usage", "no command");
    expect_clean_failure(run("frobnicate"), "unknown command", "unknown command");
    expect_clean_failure(run("render --nope 3"), "--nope", "unknown option");
    expect_clean_failure(run("render --frames"), "--frames", "missing value");
    expect_clean_failure(run("render --frames ten --out " + out.string()), "--frames",
                         "bad integer");
    expect_clean_failure(run("render --fps nan --out " + out.string()), "--fps", "NaN rate");
    expect_clean_failure(run("render --fps -30 --out " + out.string()), "--fps", "negative rate");
    expect_clean_failure(run("render --frames 0 --out " + out.string()), "--frames", "zero frames");
    expect_clean_failure(run("render --size 0x0 --out " + out.string()), "0x0", "empty size");
    expect_clean_failure(run("render --size 20000x10 --out " + out.string()), "20000x10",
                         "huge size");
    expect_clean_failure(run("render --size wide --out " + out.string()), "wide", "not a size");
    expect_clean_failure(run("render --scene nowhere --out " + out.string()), "nowhere",
                         "bad scene");
    expect_clean_failure(run("render --camera spiral --out " + out.string()), "spiral",
                         "bad camera");
    expect_clean_failure(run("render --camera orbit:speed=x --out " + out.string()), "'x'",
                         "bad param");
    expect_clean_failure(run("render"), "--out", "no output");
    expect_clean_failure(run("render --reuse always --scene courtyard --out " + out.string()),
                         "always", "bad reuse");
    expect_clean_failure(run("render --reuse cache --scene pan --out " + out.string()), "heavy",
                         "reuse needs heavy");
    expect_clean_failure(run("render --shading glossy --out " + out.string()), "glossy",
                         "bad shading");
    expect_clean_failure(
        run("render --scene courtyard --reuse cache --refresh tiles:4 --out " + out.string()),
        "tiles:4", "bad refresh kind");
    expect_clean_failure(
        run("render --scene courtyard --reuse cache --refresh tiled:0 --out " + out.string()),
        "tiled:0", "bad refresh period");
    expect_clean_failure(
        run("render --scene courtyard --reuse adaptive --threshold nan --out " + out.string()),
        "--threshold", "NaN threshold");
    expect_clean_failure(run("render --scene courtyard --pcf 99 --out " + out.string()), "--pcf",
                         "huge PCF");
    expect_clean_failure(run("render --alternate --out " + out.string()), "--stereo",
                         "alternation without a pair");
    EXPECT_EQ(run("render --help").status, 0);
    EXPECT_EQ(run("--help").status, 0);
}

TEST(CliBadInput, BrokenFramesGetOneMessageAndStatusOne) {
    fs::path dir = scratch("frames");
    std::ofstream(dir / "garbage.exr") << "this is not an OpenEXR file at all";
    std::ofstream(dir / "empty.exr");
    for (const char* name : {"garbage.exr", "empty.exr"}) {
        std::string file = (dir / name).string();
        expect_clean_failure(run("info " + file), name, std::string("info ") + name);
        expect_clean_failure(run("export " + file + " --png " + (dir / "x.png").string()), name,
                             std::string("export ") + name);
    }
    expect_clean_failure(run("info " + (dir / "missing").string()), "missing", "missing path");
    // A valid frame cut in half.
    ASSERT_EQ(run("render --frames 1 --size 64x36 --out " + (dir / "ok").string()).status, 0);
    fs::path good = dir / "ok" / "frame_00000.exr";
    auto size = fs::file_size(good);
    fs::copy_file(good, dir / "cut.exr");
    fs::resize_file(dir / "cut.exr", size / 2);
    expect_clean_failure(run("info " + (dir / "cut.exr").string()), "cut.exr", "truncated frame");
    expect_clean_failure(
        run("metrics --ref " + (dir / "ok").string() + " --test " + (dir / "cut.exr").string()),
        "cut.exr", "metrics on a truncated frame");
}

// A frame file whose header claims width x height (its dataWindow patched), pixels left as they
// were: what is read must be refused from the header, before the pixels.
void claim_size(const fs::path& file, int32_t width, int32_t height) {
    std::string bytes = reprise::test::read_text(file);
    const std::string key("dataWindow\0box2i\0", 17);
    const std::size_t at = bytes.find(key);
    ASSERT_NE(at, std::string::npos) << file;
    const int32_t box[4] = {0, 0, width - 1, height - 1};
    bytes.replace(at + key.size() + 4, sizeof box, reinterpret_cast<const char*>(box), sizeof box);
    std::ofstream(file, std::ios::binary) << bytes;
}

// Memory is bounded before it is spent: a call that would need more than --max-memory (4 GiB by
// default) is refused with the figure, quickly, before it writes anything.
TEST(CliBadInput, MemoryBeyondTheLimitIsRefusedWithTheFigure) {
    const fs::path dir = scratch("memory");
    for (const char* size : {"8192x8192", "16384x16384"}) {
        const fs::path out = dir / size;
        const Outcome r =
            run("render --frames 1 --size " + std::string(size) + " --out " + out.string());
        expect_clean_failure(r, "needs", size);
        for (const char* word : {"GiB", "limit 4 GiB", "--max-memory", size})
            EXPECT_NE(r.output.find(word), std::string::npos) << word << ":\n" << r.output;
        EXPECT_FALSE(fs::exists(out)) << size << " wrote " << out;
    }
    const fs::path small = dir / "small";
    // 640x360: 116 bytes a pixel, 25.5 MiB.
    Outcome r = run("render --frames 1 --size 640x360 --max-memory 1M --out " + small.string());
    expect_clean_failure(r, "render 640x360: needs 25.5 MiB; limit 1 MiB, --max-memory to change",
                         "--max-memory 1M");
    EXPECT_FALSE(fs::exists(small));
    r = run("--max-memory=64M render --frames 1 --size 64x36 --out " + small.string());
    EXPECT_EQ(r.status, 0) << r.output;
    for (const char* bad : {"lots", "0", "-3G", "12Q", "nan"})
        expect_clean_failure(
            run("render --max-memory " + std::string(bad) + " --out " + (dir / "bad").string()),
            "--max-memory", bad);
    expect_clean_failure(run("render --out " + (dir / "bad").string() + " --max-memory"),
                         "missing value", "--max-memory without a value");
    EXPECT_FALSE(fs::exists(dir / "bad"));

    // A frame whose header claims 16384x16384 (11 GiB of buffers) is refused before its pixels.
    const fs::path claimed = small / "frame_00000.exr";
    claim_size(claimed, 16384, 16384);
    r = run("export " + claimed.string() + " --png " + (dir / "sheet.png").string());
    expect_clean_failure(r, "needs", "a header claiming 16384x16384");
    EXPECT_NE(r.output.find("16384x16384"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "sheet.png"));
}

// Every glTF file of the assimp test models either renders or fails with one message naming it.
TEST(CliBadInput, EveryAssimpGltfModelRendersOrFailsCleanly) {
    const fs::path models = REPRISE_ASSIMP_MODELS;
    ASSERT_TRUE(fs::is_directory(models)) << "install assimp-testmodels (scripts/deps)";
    fs::path out = scratch("models");
    int rendered = 0, refused = 0;
    for (const auto& entry : fs::recursive_directory_iterator(models)) {
        std::string ext = entry.path().extension().string();
        if (ext != ".gltf" && ext != ".glb") continue;
        Outcome r = run("render --scene '" + entry.path().string() +
                        "' --frames 2 --size 96x64 --out " + out.string());
        if (r.status == 0) {
            ++rendered;
            EXPECT_TRUE(fs::exists(out / "frame_00001.exr")) << entry.path();
            continue;
        }
        ++refused;
        expect_clean_failure(r, entry.path().filename().string(), entry.path().string());
        // One message: the error line (progress output goes before it, on its own line).
        EXPECT_LE(std::count(r.output.begin(), r.output.end(), '\n'), 3) << r.output;
    }
    std::printf("[models] %d rendered, %d refused with a message\n", rendered, refused);
    EXPECT_GE(rendered, 10);
    EXPECT_GE(refused, 8);
}
