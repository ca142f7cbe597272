// The pieces of `reprise bench codec`: Bjøntegaard delta rate on analytic curves, the depth
// peers' round trips (zstd, RVL) and a tiny encode/decode through each libavcodec peer.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdio>
#include <random>

#include "bd_rate.hpp"
#include "bench_report.hpp"
#include "codec_peers.hpp"
#include "depth_peers.hpp"
#include "depth_video_peer.hpp"
#include "reprise/core/metrics.hpp"
#include "support/cli.hpp"
#include "support/codec.hpp"
#include "support/renderer.hpp"
#include "synthesized_views.hpp"

namespace reprise::cli {
namespace {

// A convex, non-linear rate-quality curve: quality in dB grows with log rate, more slowly at
// high rates.
std::vector<RatePoint> curve(double rate_scale, std::vector<double> rates) {
    std::vector<RatePoint> points;
    for (double r : rates) {
        const double lr = std::log10(r);
        points.push_back({r * rate_scale, 12.0 * lr - 0.9 * lr * lr});
    }
    return points;
}

TEST(BdRate, RateScaledByAConstantGivesThatScale) {
    const std::vector<double> rates = {1e4, 3e4, 1e5, 3e5, 1e6};
    const auto anchor = curve(1.0, rates);
    EXPECT_NEAR(bd_rate(anchor, curve(0.8, rates)), -20.0, 0.1);
    EXPECT_NEAR(bd_rate(anchor, curve(1.5, rates)), 50.0, 0.1);
    EXPECT_NEAR(bd_rate(curve(0.8, rates), anchor), 25.0, 0.1);
    // The test sampled at other rates (a partial overlap): still the same curve, 20 % cheaper.
    EXPECT_NEAR(bd_rate(anchor, curve(0.8, {2e4, 5e4, 2e5, 7e5, 2e6})), -20.0, 0.5);
}

TEST(BdRate, QualityShiftOnALogLinearCurve) {
    // quality = 10 log10(rate): +1 dB at equal rate is 10^(-0.1) of the rate at equal quality.
    std::vector<RatePoint> anchor, test;
    for (double r : {1e3, 4e3, 1.6e4, 6.4e4}) {
        anchor.push_back({r, 10.0 * std::log10(r)});
        test.push_back({r, 10.0 * std::log10(r) + 1.0});
    }
    EXPECT_NEAR(bd_rate(anchor, test), (std::pow(10.0, -0.1) - 1.0) * 100.0, 1e-6);
}

TEST(BdRate, LinearLogRateIntegratesExactly) {
    std::vector<RatePoint> points;
    for (double q : {30.0, 33.0, 37.0, 40.0}) points.push_back({std::pow(10.0, 2.0 + 0.1 * q), q});
    // ∫_31^39 (2 + 0.1 q) dq = 16 + 0.05 (39² - 31²) = 44.
    EXPECT_NEAR(integrate_log_rate(points, 31.0, 39.0), 44.0, 1e-9);
}

TEST(BdRate, NoOverlapOrTooFewPointsIsNaN) {
    const auto low = curve(1.0, {1e3, 2e3, 4e3, 8e3});
    const auto high = curve(1.0, {1e6, 2e6, 4e6, 8e6});
    EXPECT_TRUE(std::isnan(bd_rate(low, high)));
    EXPECT_TRUE(std::isnan(bd_rate(low, {{1e3, 10.0}})));
    EXPECT_TRUE(std::isnan(bd_rate(low, {{1e3, 10.0}, {2e3, 10.0}})));  // one distinct quality
}

std::vector<float> test_depth(int w, int h) {
    std::vector<float> depth(std::size_t(w) * h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float z = 2.0f + 0.01f * x + 0.003f * y * y / h;  // a smooth surface
            if ((x - w / 2) * (x - w / 2) + (y - h / 3) * (y - h / 3) < w * h / 40)
                z = 1.25f + 0.001f * x;
            if (y < h / 5) z = INFINITY;  // sky
            depth[std::size_t(y) * w + x] = z;
        }
    // The values a lossless coder must keep too.
    depth[3] = NAN;
    depth[4] = -INFINITY;
    depth[5] = 0.0f;
    depth[6] = -0.0f;
    depth[7] = -5.0f;
    depth[8] = std::numeric_limits<float>::denorm_min();
    depth[9] = std::numeric_limits<float>::max();
    return depth;
}

bool bit_equal(const std::vector<float>& a, const std::vector<float>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (std::bit_cast<uint32_t>(a[i]) != std::bit_cast<uint32_t>(b[i])) return false;
    return true;
}

TEST(DepthPeers, ZstdRoundTripIsBitExact) {
    const std::vector<float> depth = test_depth(160, 90);
    std::vector<uint8_t> bytes;
    zstd_compress_depth(depth, 3, bytes);
    EXPECT_LT(bytes.size(), depth.size() * 4);
    std::vector<float> back;
    ASSERT_TRUE(zstd_decompress_depth(bytes, depth.size(), back).ok());
    EXPECT_TRUE(bit_equal(depth, back));
    EXPECT_FALSE(zstd_decompress_depth(bytes, depth.size() + 1, back).ok());
    bytes.resize(bytes.size() / 2);
    EXPECT_FALSE(zstd_decompress_depth(bytes, depth.size(), back).ok());
}

TEST(DepthPeers, RvlFloatBitsRoundTripIsBitExact) {
    const std::vector<float> depth = test_depth(160, 90);
    std::vector<uint8_t> bytes;
    rvl_encode(depth, {}, bytes);
    std::vector<float> back;
    ASSERT_TRUE(rvl_decode(bytes, depth.size(), {}, back).ok());
    EXPECT_TRUE(bit_equal(depth, back));
    EXPECT_LT(bytes.size(), depth.size() * 3);  // a smooth surface and sky: under 24 bits/px

    // Every bit pattern, one by one.
    std::mt19937 random(7);
    std::vector<float> noise(4096);
    for (float& v : noise) v = std::bit_cast<float>(uint32_t(random()));
    rvl_encode(noise, {}, bytes);
    ASSERT_TRUE(rvl_decode(bytes, noise.size(), {}, back).ok());
    EXPECT_TRUE(bit_equal(noise, back));
}

TEST(DepthPeers, RvlInverse16KeepsInverseDepthWithinOneStep) {
    const RvlOptions options{.mode = RvlMode::Inverse16, .near = 0.5f, .far = 100.0f};
    std::vector<float> depth = test_depth(160, 90);
    std::vector<uint8_t> bytes;
    rvl_encode(depth, options, bytes);
    std::vector<float> back;
    ASSERT_TRUE(rvl_decode(bytes, depth.size(), options, back).ok());
    const double step = (1.0 / options.near - 1.0 / options.far) / 65534.0;
    for (std::size_t i = 0; i < depth.size(); ++i) {
        const float z = depth[i];
        if (z >= options.near && z <= options.far)
            ASSERT_LE(std::abs(1.0 / back[i] - 1.0 / z), 0.5 * step + 1e-9) << i;
        else
            ASSERT_TRUE(std::isinf(back[i])) << i;
    }
}

TEST(DepthPeers, RvlBadInputIsAStatus) {
    const std::vector<float> depth = test_depth(64, 32);
    std::vector<uint8_t> bytes;
    rvl_encode(depth, {}, bytes);
    std::vector<float> back;
    for (std::size_t cut : {std::size_t(0), std::size_t(1), bytes.size() / 2, bytes.size() - 1}) {
        std::vector<uint8_t> part(bytes.begin(), bytes.begin() + long(cut));
        EXPECT_FALSE(rvl_decode(part, depth.size(), {}, back).ok()) << cut;
    }
    std::vector<uint8_t> longer = bytes;
    longer.push_back(0);
    EXPECT_FALSE(rvl_decode(longer, depth.size(), {}, back).ok());
    EXPECT_FALSE(rvl_decode(bytes, depth.size() - 1, {}, back).ok());
    // Absurd run lengths.
    std::vector<uint8_t> absurd(16, 0xff);
    absurd.push_back(0x00);
    EXPECT_FALSE(rvl_decode(absurd, depth.size(), {}, back).ok());
}

// A smooth gradient with a square moving 2 px right per frame.
std::vector<Image<Rgb8>> moving_square(int w, int h, int frames) {
    std::vector<Image<Rgb8>> out(frames);
    for (int f = 0; f < frames; ++f) {
        out[f].resize(w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                Rgb8 c(uint8_t(40 + 150 * x / w), uint8_t(60 + 120 * y / h), 128);
                if (x >= 10 + 2 * f && x < 30 + 2 * f && y >= 12 && y < 32) c = Rgb8(230, 40, 30);
                out[f](x, y) = c;
            }
    }
    return out;
}

double psnr_of(const Image<Rgb8>& a, const Image<Rgb8>& b) {
    Image<glm::vec3> da, dbv;
    from_rgb8(a.view(), da);
    from_rgb8(b.view(), dbv);
    return psnr(da.view(), dbv.view());
}

void expect_round_trip(const PeerConfig& config, int w, int h, double min_psnr) {
    if (!peer_available(config.kind))
        GTEST_SKIP() << peer_name(config.kind) << " not in libavcodec";
    const auto frames = moving_square(w, h, 3);
    std::vector<PeerFrame> out;
    const Status status = encode_decode_peer(frames, config, 30.0, out);
    ASSERT_TRUE(status.ok()) << status.message();
    ASSERT_EQ(out.size(), frames.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
        EXPECT_GT(out[i].bytes, 0u) << i;
        ASSERT_EQ(out[i].decoded.width(), w);
        ASSERT_EQ(out[i].decoded.height(), h);
        const double db_seen = psnr_of(frames[i], out[i].decoded);
        std::printf("%s %s %dx%d frame %zu: %zu bytes, %.2f dB\n", peer_name(config.kind).c_str(),
                    peer_setting(config).c_str(), w, h, i, out[i].bytes, db_seen);
        EXPECT_GT(db_seen, min_psnr) << peer_setting(config) << " " << i;
        // Timed, and not absurdly: a 64x64 frame in well under a second.
        EXPECT_GT(out[i].encode_ms, 0.0);
        EXPECT_GT(out[i].decode_ms, 0.0);
        EXPECT_LT(out[i].encode_ms + out[i].decode_ms, 1000.0);
    }
    EXPECT_LT(out[1].bytes, out[0].bytes);  // an inter frame costs less than the key frame
}

TEST(CodecPeers, X264UltrafastRoundTrip) {
    expect_round_trip({.kind = PeerKind::X264, .preset = "ultrafast", .crf = 20}, 64, 64, 32.0);
}

TEST(CodecPeers, OddSizeIsPaddedAndCroppedBack) {
    expect_round_trip({.kind = PeerKind::X264, .preset = "ultrafast", .crf = 20}, 63, 37, 30.0);
}

TEST(CodecPeers, X265RoundTrip) {
    expect_round_trip({.kind = PeerKind::X265, .preset = "ultrafast", .crf = 20}, 64, 64, 32.0);
}

TEST(CodecPeers, SvtAv1RoundTrip) {
    expect_round_trip({.kind = PeerKind::SvtAv1, .preset = "10", .crf = 28}, 72, 40, 30.0);
}

TEST(CodecPeers, BadInputIsAStatus) {
    std::vector<PeerFrame> out;
    auto frames = moving_square(64, 64, 2);
    frames[1].resize(32, 32);
    EXPECT_FALSE(encode_decode_peer(frames, {}, 30.0, out).ok());
    EXPECT_FALSE(encode_decode_peer({Image<Rgb8>(1, 1)}, {}, 30.0, out).ok());
    EXPECT_TRUE(encode_decode_peer({}, {}, 30.0, out).ok());
    EXPECT_TRUE(out.empty());
}

// A 10-bit ramp with a step, as the depth peer sends 1/z.
std::vector<std::vector<uint16_t>> grey_ramps(int w, int h, int count) {
    std::vector<std::vector<uint16_t>> planes(count, std::vector<uint16_t>(std::size_t(w) * h));
    for (int i = 0; i < count; ++i)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                planes[i][std::size_t(y) * w + x] =
                    uint16_t(x < w / 2 ? 64 + 7 * x + 3 * y + i : 900 - 2 * y);
    return planes;
}

TEST(CodecPeers, GreyTenBitLosslessIsExactAndLossyStaysClose) {
    if (!peer_available(PeerKind::X265)) GTEST_SKIP() << "no x265 in this libavcodec";
    const int w = 67, h = 41;  // odd: padded and cropped back
    const auto planes = grey_ramps(w, h, 3);
    std::vector<GreyFrame> out;
    const PeerConfig lossless{.kind = PeerKind::X265, .preset = "ultrafast", .lossless = true};
    ASSERT_TRUE(encode_decode_grey_peer(planes, w, h, 10, lossless, 30.0, out).ok());
    ASSERT_EQ(out.size(), planes.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
        EXPECT_EQ(out[i].decoded, planes[i]) << i;
        EXPECT_GT(out[i].bytes, 0u);
    }
    const PeerConfig lossy{.kind = PeerKind::X265, .preset = "ultrafast", .crf = 20};
    ASSERT_TRUE(encode_decode_grey_peer(planes, w, h, 10, lossy, 30.0, out).ok());
    double sum = 0.0;
    for (std::size_t p = 0; p < planes[0].size(); ++p)
        sum += std::abs(int(out[0].decoded[p]) - int(planes[0][p]));
    EXPECT_LT(sum / double(planes[0].size()), 4.0);  // of 1023 levels
    if (peer_available(PeerKind::X264)) {            // High 10, 4:0:0
        const PeerConfig x264{.kind = PeerKind::X264, .preset = "ultrafast", .lossless = true};
        const Status s = encode_decode_grey_peer(planes, w, h, 10, x264, 30.0, out);
        ASSERT_TRUE(s.ok()) << s.message();
        EXPECT_EQ(out[1].decoded, planes[1]);
    }
    EXPECT_FALSE(encode_decode_grey_peer(planes, w, h, 8, lossless, 30.0, out).ok());
    EXPECT_FALSE(encode_decode_grey_peer(planes, w + 1, h, 10, lossless, 30.0, out).ok());
}

// The immersive-video depth peer on rendered frames: lossless 10-bit 1/z over the scene's depth
// range moves no pixel of `crossing` by more than 0.05 px for a 16.4 cm camera step, and keeps
// the background; a coarse rate moves some pixels beyond 0.25 px.
TEST(DepthVideoPeer, LosslessTenBitIsWithinAQuantisationStepAndCoarseRatesAreNot) {
    if (!peer_available(PeerKind::X265)) GTEST_SKIP() << "no x265 in this libavcodec";
    const std::vector<Frame> frames = test::render_scene("crossing", 2, 96, 64);
    DepthVideoRun run;
    const PeerConfig lossless{.kind = PeerKind::X265, .preset = "ultrafast", .lossless = true};
    ASSERT_TRUE(run_depth_video_peer(frames, 30.0, lossless, 10, 0.164f, 0.25f, run).ok());
    EXPECT_LT(run.max_error_px, 0.05);
    EXPECT_EQ(run.share_over_bound, 0.0);
    EXPECT_EQ(run.background_mismatches, 0u);
    EXPECT_GT(run.bytes, 8.0);
    const PeerConfig coarse{.kind = PeerKind::X265, .preset = "ultrafast", .crf = 45};
    ASSERT_TRUE(run_depth_video_peer(frames, 30.0, coarse, 10, 0.164f, 0.25f, run).ok());
    EXPECT_GT(run.max_error_px, 0.25);
    EXPECT_GT(run.share_over_bound, 0.0);
}

// End to end on a tiny scene: every peer's rows, finite figures, the depth coders and the page.
TEST(CliBenchCodec, TinySceneWritesRowsForEveryPeer) {
    namespace fs = std::filesystem;
    const fs::path dir =
        fs::temp_directory_path() / ("reprise-cli-bench-codec-" + std::to_string(getpid()));
    fs::remove_all(dir);
    const test::Outcome result = test::run_reprise(
        "bench codec --scenes pan --size 96x64 --frames 3 --speed-frames 0 --out " + dir.string(),
        300);
    ASSERT_EQ(result.status, 0) << result.output;
    EXPECT_NE(result.output.find("targets (issue 8"), std::string::npos) << result.output;
    // View depth: the bound and the measured error, within it.
    EXPECT_NE(result.output.find("depth to the view bound"), std::string::npos) << result.output;
    EXPECT_NE(result.output.find("within the bound"), std::string::npos) << result.output;
    EXPECT_EQ(result.output.find("OUTSIDE the bound"), std::string::npos) << result.output;
    std::ifstream csv(dir / "codec.csv");
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line, "scene,codec,setting,frame,bits,psnr,ssim,flip,encode_ms,decode_ms");
    std::map<std::string, int> rows;
    while (std::getline(csv, line)) {
        std::vector<std::string> cells;
        std::stringstream stream(line);
        for (std::string cell; std::getline(stream, cell, ',');) cells.push_back(cell);
        ASSERT_EQ(cells.size(), 10u) << line;
        ++rows[cells[1]];
        EXPECT_GT(std::stod(cells[4]), 0.0) << line;   // bits
        EXPECT_GT(std::stod(cells[5]), 20.0) << line;  // PSNR: figures seen 27..45 dB
    }
    for (PeerKind kind : {PeerKind::X264, PeerKind::X265, PeerKind::SvtAv1}) {
        if (!peer_available(kind)) continue;
        const int rate_points = kind == PeerKind::X264 ? 3 * 4 : 4;  // x264: three presets
        EXPECT_EQ(rows[peer_name(kind)], rate_points * 3) << peer_name(kind);
    }
    std::ifstream depth(dir / "depth.csv");
    std::string depth_text((std::istreambuf_iterator<char>(depth)), {});
    EXPECT_NE(depth_text.find("pan,zstd-3,2,"), std::string::npos);
    EXPECT_NE(depth_text.find("pan,rvl-float,2,"), std::string::npos);
    EXPECT_TRUE(fs::exists(dir / "index.html"));
    fs::remove_all(dir);
}

// The speed run alternates the codecs over --repeat rounds and keeps each one's fastest: every
// round runs, every row of speed.csv has its figures.
TEST(CliBenchCodec, TheSpeedRunKeepsEachCodecsFastestRound) {
    namespace fs = std::filesystem;
    const fs::path dir =
        fs::temp_directory_path() / ("reprise-cli-bench-codec-speed-" + std::to_string(getpid()));
    fs::remove_all(dir);
    const test::Outcome result = test::run_reprise(
        "bench codec --scenes pan --size 64x48 --frames 2 --qps 28,34 --speed-size 64x48 "
        "--speed-frames 6 --repeat 2 --out " +
            dir.string(),
        300);
    ASSERT_EQ(result.status, 0) << result.output;
    for (const char* text : {"round 1/2", "round 2/2", "the fastest of 2 alternating rounds",
                             "encode at least as fast as x264 veryfast"})
        EXPECT_NE(result.output.find(text), std::string::npos) << text << "\n" << result.output;
    std::ifstream csv(dir / "speed.csv");
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line, "size,frames,codec,setting,encode_ms,decode_ms,encode_ms_warm,decode_ms_warm");
    int rows = 0;
    while (std::getline(csv, line)) {
        ++rows;
        EXPECT_EQ(line.rfind("64x48,6,", 0), 0u) << line;
        const std::size_t after_setting = line.find(',', line.find(',', 8) + 1);
        EXPECT_GT(std::stod(line.substr(after_setting + 1)), 0.0) << line;  // encode ms
    }
    EXPECT_EQ(rows, 5);  // x264 veryfast, ultrafast, the default stream twice, lossless depth
    fs::remove_all(dir);
}

// The client's views (1-3 display periods ahead, the other eye) from the default stream's decoded
// depth stay within 0.2 dB of the same views from rendered depth; with depth coded 32 times
// coarser (E = 8 px, motion per pixel so that its bound does not refine the depth) they do not.
// Measured at 160x96, 4 frames: crossing (still camera, cars) worst -0.01 dB and fence (orbit)
// -0.04 dB; at E = 8 px, crossing -2.35 dB and fence -4.71 dB.
TEST(SynthesizedViews, DecodedDepthWarpsAsWellAsRenderedDepth) {
    for (const char* name : {"crossing", "fence"}) {
        server::Scene scene;
        server::CameraPath path;
        ASSERT_TRUE(server::load_scene(name, scene, path).ok());
        const std::vector<Frame> frames = test::render_scene(name, 4, 160, 96);
        double worst[2] = {0.0, 0.0};
        for (float bound : {0.25f, 8.0f}) {
            // Motion to 1/8 px per pixel, so that its bound does not refine the depth.
            const codec::EncoderOptions options{.depth = codec::DepthMode::View,
                                                .view_error_px = bound,
                                                .motion_error_px = bound > 1.0f ? 0.0f : 0.25f};
            const auto decoded = test::decode_all(test::encode_all(frames, options).packets);
            ASSERT_EQ(decoded.size(), frames.size());
            SynthesizedViewScorer scorer(test::shared_renderer(), scene, path, 30.0);
            SynthesizedViews views;
            for (std::size_t i = 0; i < frames.size(); ++i)
                ASSERT_TRUE(scorer.add(int(i), frames[i], decoded[i], views).ok());
            for (int v = 0; v < SynthesizedViews::kViews; ++v)
                worst[bound > 1.0f] = std::min(worst[bound > 1.0f], views.loss_db(v));
        }
        EXPECT_GE(worst[0], -0.2) << name;
        EXPECT_LT(worst[1], -0.2) << name << ": coarse depth not seen";
    }
}

}  // namespace
}  // namespace reprise::cli
