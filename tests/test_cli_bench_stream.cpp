// `reprise bench stream` end to end at a tiny size: the peers of issue 23 beside reprise at 100 ms
// round trip, with figures that follow from what each method shows.
#include <gtest/gtest.h>
#include <unistd.h>

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

struct Row {
    double kbps = 0, psnr = 0, latency_mean_ms = 0, latency_p95_ms = 0;
};

std::map<std::string, Row> read_summary(const fs::path& file) {
    std::map<std::string, Row> rows;
    std::ifstream in(file);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        std::stringstream stream(line);
        for (std::string field; std::getline(stream, field, ',');) f.push_back(field);
        if (f.size() < 9) continue;
        rows[f[1]] = {std::stod(f[2]), std::stod(f[3]), std::stod(f[6]), std::stod(f[7])};
    }
    return rows;
}

TEST(CliBenchStream, PeersBesideTheStreamAtOneHundredMillisecondsRoundTrip) {
    const fs::path dir =
        fs::temp_directory_path() / ("reprise-cli-bench-stream-" + std::to_string(getpid()));
    fs::remove_all(dir);
    const Outcome r = run_reprise(
        "bench stream --size 128x72 --conditions rtt100ms --duration 1.5 "
        "--qps 34 --out " +
            dir.string(),
        240);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("at qp 34"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("rtt100ms: coded "), std::string::npos) << r.output;
    const std::map<std::string, Row> rows = read_summary(dir / "stream_summary.csv");
    for (const char* method : {"reprise", "repetition", "x264-crf23", "x264-crf15", "x264-crf23+tw",
                               "x264+depth10", "reprise-lowres4"})
        ASSERT_TRUE(rows.count(method)) << method << " missing:\n" << r.output;
    const Row& ours = rows.at("reprise");
    const Row& repeated = rows.at("repetition");
    const Row& video = rows.at("x264-crf23");
    // Extrapolated to each display pose against the newest frame shown as it is, 100 ms late
    // (measured 28.7 against 23.0 dB).
    EXPECT_GE(ours.psnr, repeated.psnr + 3.0) << r.output;
    // A frame shown as it arrives is at least the round trip old; a warped one the client's
    // own time.
    EXPECT_GE(repeated.latency_mean_ms, 100.0) << r.output;
    EXPECT_LT(ours.latency_p95_ms, 50.0) << r.output;
    // `pan` only translates: turning the video by the rotation between poses changes nothing.
    EXPECT_NEAR(rows.at("x264-crf23+tw").psnr, video.psnr, 0.01) << r.output;
    EXPECT_EQ(rows.at("x264-crf23+tw").kbps, video.kbps);
    // The colour + depth peer sends the same video plus its depth, and its extrapolation beats
    // the video it starts from.
    EXPECT_GT(rows.at("x264+depth10").kbps, video.kbps) << r.output;
    EXPECT_GE(rows.at("x264+depth10").psnr, video.psnr + 3.0) << r.output;
    EXPECT_GT(rows.at("x264-crf15").kbps, video.kbps) << r.output;
    std::ifstream html(dir / "index.html");
    std::stringstream page;
    page << html.rdbuf();
    EXPECT_NE(page.str().find("<svg"), std::string::npos);
    fs::remove_all(dir);
}

TEST(CliBenchStream, RefusesASecondQpAndAnUnknownCondition) {
    Outcome r = run_reprise("bench stream --qps 28,34 --duration 1", 60);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.output.find("--qps: stream takes one qp in 0..51, not '28,34'"), std::string::npos)
        << r.output;
    r = run_reprise("bench stream --qps 52 --duration 1", 60);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.output.find("not '52'"), std::string::npos) << r.output;
    r = run_reprise("bench stream --conditions clean,marsh --duration 1", 60);
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.output.find("unknown condition 'marsh'"), std::string::npos) << r.output;
}

}  // namespace
