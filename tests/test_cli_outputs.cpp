// Nothing a user gives reprise is lost: outputs that would overwrite inputs are refused, files are
// written whole, a killed run resumes to the same bytes, and silently odd input is refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <string>
#include <thread>

#include "reprise/core/exr.hpp"
#include "support/cli.hpp"

namespace fs = std::filesystem;
using reprise::test::contents;
using reprise::test::differences;
using reprise::test::frames;
using reprise::test::fresh_directory;
using reprise::test::Outcome;
using reprise::test::q;
using reprise::test::read_text;

namespace {

Outcome run(const std::string& arguments) { return reprise::test::run_reprise(arguments, 300); }

fs::path scratch(const std::string& name) {
    return fresh_directory(fs::temp_directory_path() / ("reprise-outputs-" + name));
}

void expect_refused(const Outcome& r, const std::string& must_mention, const std::string& what) {
    EXPECT_TRUE(r.status == 1 || r.status == 2) << what << ": status " << r.status << "\n"
                                                << r.output;
    EXPECT_NE(r.output.find(must_mention), std::string::npos) << what << ":\n" << r.output;
}

fs::path render(const std::string& name, const std::string& extra = "") {
    fs::path dir = scratch(name);
    Outcome r = run("render --scene pan --frames 4 --size 64x36 --aa 1 " + extra + " --out " +
                    q(dir / "x"));
    EXPECT_EQ(r.status, 0) << r.output;
    return dir;
}

}  // namespace

// The report: `fruc --in out/x --out out/x` overwrote inputs 2 and 3 before reading them.
TEST(CliOutputs, OutputsThatWouldOverwriteInputsAreRefused) {
    const fs::path dir = render("overlap");
    const fs::path x = dir / "x";
    const auto before = contents(x);
    ASSERT_EQ(frames(x).size(), 4u);
    fs::create_directory_symlink(x, dir / "link");
    const std::string in = " --in " + q(x);
    expect_refused(run("fruc" + in + " --out " + q(x)), "is the input", "fruc, same folder");
    expect_refused(run("fruc" + in + " --out " + q(x / "sub")), "inside the input folder",
                   "fruc, a folder inside");
    expect_refused(run("fruc" + in + " --out " + q(dir / "link")), "is the input",
                   "fruc, a symbolic link to the input folder");
    expect_refused(run("fruc --in " + q(x / "frame_00001.exr") + " --out " + q(x)),
                   "holds the input", "fruc, the folder of a single input frame");
    expect_refused(run("fruc" + in + " --ui " + q(dir / "link") + " --out " + q(x)),
                   "--overwrite-inputs", "fruc, the UI sequence");
    expect_refused(run("stereo" + in + " --out " + q(x)), "is the input", "stereo, same folder");
    fs::create_directories(dir / "st");
    fs::create_directory_symlink(x, dir / "st" / "left");
    expect_refused(run("stereo" + in + " --out " + q(dir / "st")), "is the input",
                   "stereo, OUT/left a symbolic link to the input");
    expect_refused(run("upsample" + in + " --low " + q(x) + " --out " + q(x)), "is the input",
                   "upsample");
    expect_refused(run("encode" + in + " --out " + q(x / "frame_00002.exr")), "inside the input",
                   "encode over an input frame");
    expect_refused(
        run("metrics --ref " + q(x) + " --test " + q(x) + " --csv " + q(x / "frame_00003.exr")),
        "inside the input", "metrics CSV over an input frame");
    expect_refused(run("export " + q(x) + " --png " + q(x / "frame_00000.exr")), "inside the input",
                   "export over an input frame");
    EXPECT_EQ(differences(contents(x), before), "") << "an input changed";

    // Writing beside the inputs where nothing is read stays allowed: a CSV in the frame folder.
    EXPECT_EQ(run("metrics --ref " + q(x) + " --test " + q(x) + " --csv " + q(x / "m.csv")).status,
              0);
}

// Said explicitly, the output may replace the inputs, and is then what it would have been
// elsewhere: frames are staged and moved into place after every input was read.
TEST(CliOutputs, OverwritingInputsWhenAskedGivesTheSameFrames) {
    const fs::path dir = render("inplace");
    ASSERT_EQ(run("fruc --in " + q(dir / "x") + " --out " + q(dir / "y")).status, 0);
    fs::copy(dir / "x", dir / "z");
    Outcome r = run("fruc --in " + q(dir / "z") + " --out " + q(dir / "z") + " --overwrite-inputs");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_EQ(frames(dir / "z").size(), 7u);
    EXPECT_EQ(differences(frames(dir / "z"), frames(dir / "y")), "");
    EXPECT_FALSE(fs::exists(dir / "z" / ".reprise-staging"));
}

// A run killed mid-way leaves only whole frames; --resume finishes it with the bytes an
// uninterrupted run writes.
TEST(CliOutputs, KilledFrucResumesToTheSameBytes) {
    const fs::path dir = scratch("resume");
    const fs::path in = dir / "in", whole = dir / "whole", killed = dir / "killed";
    ASSERT_EQ(run("render --scene crossing --frames 16 --size 160x90 --aa 1 --out " + q(in)).status,
              0);
    const std::string fruc = "fruc --in " + q(in) + " --factor 4 --refine on";
    ASSERT_EQ(run(fruc + " --out " + q(whole)).status, 0);
    const std::size_t total = frames(whole).size();
    ASSERT_EQ(total, 61u);
    // Killed (SIGKILL: no clean-up of any kind) once frame 20 of 61 is on disk.
    const std::string wait_and_kill =
        "sh -c \"" REPRISE_BINARY " " + fruc + " --out " + q(killed) +
        " >/dev/null 2>&1 & p=\\$!; i=0; while [ ! -e " + q(killed / "frame_00020.exr") +
        " ] && [ \\$i -lt 3000 ]; do sleep 0.01; i=\\$((i+1)); done; kill -9 \\$p; wait \\$p\"";
    reprise::test::run_output(wait_and_kill);
    const std::size_t left = frames(killed).size();
    ASSERT_GE(left, 20u);
    ASSERT_LT(left, total) << "the run ended before it was killed";
    const auto whole_frames = frames(whole);
    for (const auto& [name, bytes] : frames(killed))
        EXPECT_TRUE(bytes == whole_frames.at(name)) << name << ": a frame on disk is not whole";

    Outcome other = run("fruc --in " + q(in) + " --factor 2 --resume --out " + q(killed));
    EXPECT_EQ(other.status, 1) << other.output;
    EXPECT_NE(other.output.find("another run"), std::string::npos) << other.output;

    Outcome r = run(fruc + " --resume --out " + q(killed));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("resuming"), std::string::npos) << r.output;
    EXPECT_EQ(differences(frames(killed), whole_frames), "");
    for (const auto& [name, bytes] : contents(killed))
        EXPECT_FALSE(name.ends_with(".tmp")) << name << " left behind";
}

// Stereo with the temporal fill reads the frame before: resumed after losing frames 5.., with
// frame 5 of one eye only, it writes what the whole run wrote.
TEST(CliOutputs, StereoResumesToTheSameBytes) {
    const fs::path dir = scratch("stereo-resume");
    const fs::path in = dir / "in", whole = dir / "whole", cut = dir / "cut";
    ASSERT_EQ(run("render --scene pan --frames 8 --size 96x54 --aa 1 --out " + q(in)).status, 0);
    const std::string stereo = "stereo --temporal --in " + q(in);
    ASSERT_EQ(run(stereo + " --out " + q(whole)).status, 0);
    ASSERT_EQ(run(stereo + " --out " + q(cut)).status, 0);
    for (int i = 5; i < 8; ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%05d.exr", i);
        if (i > 5) fs::remove(cut / "left" / name);
        fs::remove(cut / "right" / name);
    }
    Outcome r = run(stereo + " --resume --out " + q(cut));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("restarting at input 4"), std::string::npos) << r.output;
    EXPECT_EQ(differences(frames(cut), frames(whole)), "");
}

// Input that was accepted without a word: now refused, naming what.
TEST(CliOutputs, SilentlyOddInputIsRefused) {
    const fs::path dir = render("odd");
    const fs::path x = dir / "x";
    ASSERT_EQ(
        run("render --scene pan --frames 1 --size 48x32 --aa 1 --out " + q(dir / "small")).status,
        0);
    fs::copy_file(dir / "small" / "frame_00000.exr", x / "frame_00004.exr");
    const std::string in = " --in " + q(x);
    expect_refused(run("fruc" + in + " --out " + q(dir / "f")), "needs frames of one size",
                   "fruc, mixed sizes");
    expect_refused(run("stereo" + in + " --out " + q(dir / "s")), "48x32", "stereo, mixed sizes");
    expect_refused(run("encode" + in + " --out " + q(dir / "e.rps")), "64x36",
                   "encode, mixed sizes");
    EXPECT_FALSE(fs::exists(dir / "f" / "frame_00000.exr")) << "fruc wrote before refusing";
    fs::remove(x / "frame_00004.exr");

    expect_refused(run("encode" + in + " --quality -5 --out " + q(dir / "e.rps")), "--quality",
                   "negative quality");
    expect_refused(run("encode" + in + " --depth bounded: --out " + q(dir / "e.rps")),
                   "bounded:", "a bound without its number");
    expect_refused(run("encode" + in + " --depth boundedly --out " + q(dir / "e.rps")), "boundedly",
                   "a word that starts as 'bounded'");
    expect_refused(run("stereo" + in + " --ipd -5 --out " + q(dir / "s")), "--ipd", "negative IPD");
    expect_refused(run("stereo" + in + " --ipd 0 --out " + q(dir / "s")), "--ipd", "zero IPD");
    fs::create_directory(dir / "stream");
    expect_refused(run("encode" + in + " --out " + q(dir / "stream")), "is a folder",
                   "encode into a folder");
    for (const auto& entry : fs::directory_iterator(dir))
        EXPECT_EQ(entry.path().string().find("partial"), std::string::npos)
            << entry.path() << " left behind";
    EXPECT_NE(run("render --help").output.find("orbit:speed=0.5"), std::string::npos);
    expect_refused(run("render --camera orbit,speed=2 --out " + q(dir / "r")), "colon",
                   "a comma where the colon belongs");
}

// A killed encode leaves whole packets in a hidden partial stream (and perhaps a torn last one);
// --resume decodes them into the encoder's state and writes the bytes of an uninterrupted encode,
// at constant quality and under rate control alike.
TEST(CliOutputs, KilledEncodeResumesToTheSameBytes) {
    const fs::path dir = scratch("encode-resume");
    const fs::path in = dir / "in";
    ASSERT_EQ(
        run("render --scene crossing --frames 24 --size 320x180 --aa 1 --out " + q(in)).status, 0);
    // Frames 4.. at 15 fps (a server stepping down): rate control divides the bitrate by each
    // frame's rate, which a resumed encode takes from the frames' headers.
    for (int i = 4; i < 24; ++i) {
        const std::string file =
            (in / ("frame_" + std::string(i < 10 ? "0000" : "000") + std::to_string(i) + ".exr"))
                .string();
        reprise::Frame f;
        ASSERT_TRUE(reprise::read_frame(file, f).ok()) << file;
        f.fps = 15.0;
        ASSERT_TRUE(reprise::write_frame(file, f).ok()) << file;
    }
    for (const std::string options : {"--qp 30", "--bitrate 400"}) {
        const std::string encode = "encode --in " + q(in) + " " + options;
        const fs::path whole = dir / "whole.rps", killed = dir / "killed.rps";
        const fs::path partial = dir / ".killed.rps.partial";
        fs::remove(killed);
        ASSERT_EQ(run(encode + " --out " + q(whole)).status, 0) << options;
        const std::string stream = read_text(whole);
        // Killed once half of the stream is on disk (the key frame is a third of it), then its
        // last bytes torn off as a write cut short would leave them.
        const std::string wait_and_kill =
            "sh -c \"" REPRISE_BINARY " " + encode + " --out " + q(killed) +
            " >/dev/null 2>&1 & p=\\$!; i=0; while [ \\$(stat -c %s " + q(partial) +
            " 2>/dev/null || echo 0) -lt " + std::to_string(stream.size() / 2) +
            " ] && [ \\$i -lt 3000 ]; do sleep 0.01; i=\\$((i+1)); done; kill -9 \\$p; wait \\$p\"";
        reprise::test::run_output(wait_and_kill);
        ASSERT_FALSE(fs::exists(killed)) << options << ": the encode ended before it was killed";
        const std::uintmax_t left = fs::file_size(partial);
        ASSERT_GE(left, stream.size() / 2) << options;
        ASSERT_LT(left, stream.size()) << options;
        EXPECT_EQ(read_text(partial), stream.substr(0, left)) << options;
        fs::resize_file(partial, left - 7);

        Outcome r = run(encode + " --resume --out " + q(killed));
        ASSERT_EQ(r.status, 0) << options << "\n" << r.output;
        EXPECT_NE(r.output.find("torn last packet dropped"), std::string::npos) << r.output;
        EXPECT_TRUE(read_text(killed) == stream) << options << ": the resumed stream differs";
        EXPECT_FALSE(fs::exists(partial)) << options;
    }
}
