// `reprise bench stereo --in` end to end on a rendered pair read back: every setting and peer
// scored, eye alternation included, and a folder without the right eye refused by name.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli.hpp"

namespace fs = std::filesystem;
using namespace reprise::test;

namespace {

// Mean PSNR per "method setting" over the CSV's rows (disoccluded-only rows left out).
std::map<std::string, double> mean_psnr(const fs::path& csv_path, std::map<std::string, int>& n) {
    std::ifstream csv(csv_path);
    std::string line;
    std::getline(csv, line);
    std::map<std::string, double> sum;
    while (std::getline(csv, line)) {
        std::vector<std::string> f;
        std::stringstream stream(line);
        for (std::string field; std::getline(stream, field, ',');) f.push_back(field);
        if (f.size() != 8 || f[2].find("+disoccluded") != std::string::npos) continue;
        sum[f[1] + " " + f[2]] += std::stod(f[4]);
        ++n[f[1] + " " + f[2]];
    }
    for (auto& [key, value] : sum) value /= n[key];
    return sum;
}

}  // namespace

TEST(CliBenchStereo, ReadsAPairFromFoldersAndScoresEverySetting) {
    const fs::path dir =
        fs::temp_directory_path() / ("reprise-cli-bench-stereo-" + std::to_string(getpid()));
    fs::remove_all(dir);
    Outcome r = run_reprise("render --scene crossing --frames 3 --size 96x54 --stereo 0.1 --out " +
                                (dir / "pair").string(),
                            120);
    ASSERT_EQ(r.status, 0) << r.output;
    r = run_reprise("bench stereo --in " + (dir / "pair").string() +
                        " --frames 2 --repeat 1 --out " + (dir / "report").string(),
                    300);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("ratio n/a (read, not rendered)"), std::string::npos) << r.output;
    std::map<std::string, int> rows;
    const std::map<std::string, double> psnr = mean_psnr(dir / "report" / "stereo.csv", rows);
    for (const char* key :
         {"ours grid+pullpush", "ours grid+pullpush+history", "ours grid+patch",
          "dibr-splat nofill", "dibr-splat telea", "cv-remap linear", "alternate grid+pullpush"}) {
        ASSERT_EQ(rows[key], 2) << key;
        EXPECT_TRUE(std::isfinite(psnr.at(key))) << key;
        std::printf("[bench stereo --in] %s: %.2f dB\n", key, psnr.at(key));
    }
    EXPECT_GT(psnr.at("ours grid+pullpush"), 28.0);
    EXPECT_GT(psnr.at("dibr-splat telea"), psnr.at("dibr-splat nofill"));
    EXPECT_TRUE(fs::exists(dir / "report" / "index.html"));

    fs::remove_all(dir / "pair" / "right");
    r = run_reprise(
        "bench stereo --in " + (dir / "pair").string() + " --out " + (dir / "report").string(), 60);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.output.find("right"), std::string::npos) << r.output;
    fs::remove_all(dir);
}
