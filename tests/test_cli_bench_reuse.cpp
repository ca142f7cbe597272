// `reprise bench reuse` end to end at a tiny size: CSV rows per frame and setting, the summary with
// issue 11's targets, the HTML report.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli.hpp"

namespace fs = std::filesystem;
using namespace reprise::test;

namespace {

std::vector<std::string> fields(const std::string& line) {
    std::vector<std::string> out;
    std::stringstream stream(line);
    std::string field;
    while (std::getline(stream, field, ',')) out.push_back(field);
    return out;
}

TEST(CliBenchReuse, WritesRowsSummaryAndReport) {
    const fs::path dir =
        fs::temp_directory_path() / ("reprise-cli-bench-reuse-" + std::to_string(getpid()));
    fs::remove_all(dir);
    const Outcome r = run_reprise(
        "bench reuse --quick --scenes courtyard --size 64x36 --frames 3 --out " + dir.string(),
        300);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("Targets (issue 11)"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("uniform at equal pixels shaded"), std::string::npos) << r.output;

    std::ifstream csv(dir / "reuse.csv");
    ASSERT_TRUE(csv);
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line.rfind("scene,method,setting,frame,psnr,ssim,flip,ms,", 0), 0u) << line;
    const std::vector<std::string> header = fields(line);
    std::set<std::string> methods;
    int rows = 0;
    while (std::getline(csv, line)) {
        const std::vector<std::string> f = fields(line);
        ASSERT_EQ(f.size(), header.size()) << line;
        methods.insert(f[1]);
        const double hit_rate = std::stod(f[header.size() - 3]),
                     shaded = std::stod(f[header.size() - 2]);
        const double above = std::stod(f[header.size() - 1]);
        EXPECT_TRUE(hit_rate >= 0 && hit_rate <= 1 && shaded >= 0 && shaded <= 1) << line;
        EXPECT_TRUE(above >= 0 && above <= 1) << line;
        if (f[3] == "0") {
            EXPECT_EQ(shaded, 1.0) << "frame 0 has no cache: " << line;
        }
        ++rows;
    }
    EXPECT_EQ(rows, 6 * 3);  // the quick settings, 3 frames each
    EXPECT_TRUE(methods.count("tiled") && methods.count("blocks") && methods.count("adaptive"));
    EXPECT_TRUE(fs::exists(dir / "reuse_summary.csv"));
    std::ifstream html(dir / "index.html");
    std::stringstream page;
    page << html.rdbuf();
    EXPECT_NE(page.str().find("<svg"), std::string::npos);
    fs::remove_all(dir);
}

}  // namespace
