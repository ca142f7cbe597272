// `reprise bench paths --backend gles` end to end at a tiny size: the GPU stages' rows beside the
// CPU's, results within 50 dB of the CPU's, and a wrong backend named.
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "support/cli.hpp"

using namespace reprise::test;

namespace {

TEST(CliBenchPaths, GlesRowsBesideTheCpu) {
    const Outcome r = run_reprise("bench paths --backend gles --sizes 96x64 --frames 2", 300);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("96x64      interpolate grid+pullpush"), std::string::npos) << r.output;
    for (const char* stage : {"reproject RGBA", "pull-push (depth)"}) {
        const std::size_t at = r.output.find(std::string("96x64      ") + stage);
        ASSERT_NE(at, std::string::npos) << stage << "\n" << r.output;
        // size, stage (two words), 8 figures: the last is the GPU's PSNR against the CPU's.
        std::istringstream row(r.output.substr(at, r.output.find('\n', at) - at));
        std::string size, word, second, last;
        row >> size >> word >> second;
        for (int i = 0; i < 8; ++i) row >> last;
        EXPECT_GE(std::stod(last), 50.0) << stage;  // inf on llvmpipe: identical
    }
}

TEST(CliBenchPaths, UnknownBackendIsNamed) {
    const Outcome r = run_reprise("bench paths --backend vulkan --sizes 96x64 --frames 2", 60);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.output.find("bench paths: --backend 'vulkan': expected cpu or gles"),
              std::string::npos)
        << r.output;
}

}  // namespace
