// `reprise bench paths --backend gles` and reprise-gles-bench end to end at a tiny size: the GPU
// stages' rows beside the CPU's, results within 50 dB of the CPU's, and bad arguments named.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "support/cli.hpp"

using namespace reprise::test;

namespace {

// Each GPU stage's row: size, stage (two words), 10 figures, the last the GPU's PSNR against the
// CPU's (inf on llvmpipe for all but the grid's).
void expect_gles_rows(const std::string& output) {
    for (const char* stage : {"reproject RGBA", "pull-push (depth)", "stereo-eye splat+pp",
                              "interpolate splat+pp", "extrapolate splat+pp", "stereo-eye grid+pp",
                              "extrapolate grid+pp", "interpolate grid+pp"}) {
        const std::size_t at = output.find(std::string("96x64      ") + stage);
        ASSERT_NE(at, std::string::npos) << stage << "\n" << output;
        std::istringstream row(output.substr(at, output.find('\n', at) - at));
        std::string size, word, second, figure;
        row >> size >> word >> second;
        std::vector<std::string> figures;
        while (row >> figure) figures.push_back(figure);
        ASSERT_EQ(figures.size(), 10u) << stage << "\n" << output;
        EXPECT_GE(std::stod(figures.back()), 50.0) << stage;
        EXPECT_GT(std::stod(figures[7]), 0.0) << stage;  // the texture entry point was timed
    }
}

TEST(CliBenchPaths, GlesRowsBesideTheCpu) {
    const Outcome r = run_reprise("bench paths --backend gles --sizes 96x64 --frames 2", 300);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("96x64      interpolate grid+pullpush"), std::string::npos) << r.output;
    expect_gles_rows(r.output);
}

// The same table from the executable that needs only the renderer's and the GPU's libraries.
TEST(CliBenchPaths, TheStandaloneGlesBenchPrintsTheSameRows) {
    const std::string out =
        run_output("timeout 300 " REPRISE_GLES_BENCH " --sizes 96x64 --frames 2 2>&1; echo rc=$?");
    EXPECT_NE(out.find("rc=0"), std::string::npos) << out;
    expect_gles_rows(out);
    const std::string bad =
        run_output("timeout 60 " REPRISE_GLES_BENCH " --frames 0 2>&1; echo rc=$?");
    EXPECT_NE(bad.find("--frames must be at least 1"), std::string::npos) << bad;
    EXPECT_NE(bad.find("rc=2"), std::string::npos) << bad;
}

TEST(CliBenchPaths, UnknownBackendIsNamed) {
    const Outcome r = run_reprise("bench paths --backend vulkan --sizes 96x64 --frames 2", 60);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.output.find("bench paths: --backend 'vulkan': expected cpu or gles"),
              std::string::npos)
        << r.output;
}

}  // namespace
