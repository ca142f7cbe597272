// The C interface gives what the C++ classes give, bit for bit: the frame-rate converter's
// outputs, the other eye, the encoder's packets and the decoder's frames, on the same synthetic
// frames.
#include <gtest/gtest.h>

#include <cstddef>
#include <cstring>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "reprise.h"
#include "reprise/codec/codec.hpp"
#include "reprise/stereo/rig.hpp"
#include "reprise/stereo/synthesize.hpp"
#include "reprise/warp/fruc.hpp"
#include "support/frames.hpp"

namespace reprise {
namespace {

constexpr int kW = 64, kH = 48;

// Three frames of random colour moving 3 px right per frame (wrapping around), seen by a
// perspective camera.
std::vector<Frame> frames() {
    const Frame texture = test::flat_frame(kW, kH, 4.0f, {-3.0f, 0.0f}, 7);
    std::vector<Frame> out;
    for (int k = 0; k < 3; ++k) {
        Frame f = texture;
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x) f.color(x, y) = texture.color((x - 3 * k + kW) % kW, y);
        f.depth(5, 5) = test::kInf;  // a background pixel
        f.camera.projection = glm::perspective(0.9f, float(kW) / kH, 0.1f, 100.0f);
        f.camera.prev_projection = f.camera.projection;
        f.camera.view = glm::translate(glm::mat4(1.0f), {-0.05f * k, 0.0f, 0.0f});
        f.camera.prev_view = glm::translate(glm::mat4(1.0f), {-0.05f * (k - 1), 0.0f, 0.0f});
        f.camera.near = 0.1f;
        f.camera.far = 100.0f;
        f.camera.time = k / 30.0;
        f.fps = 30.0;
        out.push_back(std::move(f));
    }
    return out;
}

template <class T>
reprise_image image_of(const Image<T>& image, reprise_format format) {
    return {const_cast<T*>(image.data()),       image.width(), image.height(),
            int64_t(image.width() * sizeof(T)), format,        0};
}

void copy_matrix(const glm::mat4& m, float* a) { std::memcpy(a, &m[0][0], 16 * sizeof(float)); }

reprise_gbuffer gbuffer_of(const Frame& f) {
    reprise_gbuffer g;
    EXPECT_EQ(reprise_gbuffer_init(&g, sizeof g), REPRISE_OK);
    g.color = image_of(f.color, REPRISE_FORMAT_RGBA32_FLOAT);
    g.depth = image_of(f.depth, REPRISE_FORMAT_R32_FLOAT);
    g.motion = image_of(f.motion, REPRISE_FORMAT_RG32_FLOAT);
    copy_matrix(f.camera.view, g.camera.view);
    copy_matrix(f.camera.projection, g.camera.projection);
    copy_matrix(f.camera.prev_view, g.camera.prev_view);
    copy_matrix(f.camera.prev_projection, g.camera.prev_projection);
    g.camera.near_plane = f.camera.near;
    g.camera.far_plane = f.camera.far;
    g.camera.time = f.camera.time;
    g.camera.valid = 1;
    g.fps = f.fps;
    return g;
}

// An output G-buffer writing into `f`'s colour, depth and motion, sized kW x kH.
reprise_gbuffer output_into(Frame& f) {
    f.color.resize(kW, kH);
    f.depth.resize(kW, kH);
    f.motion.resize(kW, kH);
    return gbuffer_of(f);
}

// Without and with a reported cut before the last frame (reset = Camera::cut).
class CapiConverter : public testing::TestWithParam<bool> {};

TEST_P(CapiConverter, OutputsAreTheFrameRateConverters) {
    const bool cut = GetParam();
    const std::vector<Frame> input = frames();
    warp::FrameRateConverter cpp;
    ASSERT_TRUE(warp::FrameRateConverter::create(2, warp::FrucOptions{}, cpp).ok());
    reprise_converter* c = nullptr;
    ASSERT_EQ(reprise_converter_create(REPRISE_ABI_VERSION, nullptr, &c), REPRISE_OK);
    int compared = 0;
    for (const Frame& f : input) {
        const bool reset = cut && &f == &input.back();
        Frame sent = f;
        if (reset) sent.camera.cut = Cut::Yes;
        ASSERT_TRUE(cpp.send(sent).ok());
        reprise_gbuffer g = gbuffer_of(f);
        g.reset = reset ? REPRISE_RESET_YES : REPRISE_RESET_UNKNOWN;
        ASSERT_EQ(reprise_converter_send(c, &g), REPRISE_OK) << reprise_last_error();
        Frame want, got;
        while (cpp.receive(want)) {
            reprise_gbuffer out = output_into(got);
            ASSERT_EQ(reprise_converter_receive(c, &out), REPRISE_OK) << reprise_last_error();
            EXPECT_TRUE(test::same_bits(want.color, got.color)) << "output " << compared;
            EXPECT_TRUE(test::same_bits(want.depth, got.depth)) << "output " << compared;
            EXPECT_TRUE(test::same_bits(want.motion, got.motion)) << "output " << compared;
            EXPECT_EQ(want.camera.time, out.camera.time);
            EXPECT_EQ(0, std::memcmp(&want.camera.view[0][0], out.camera.view, 64));
            ++compared;
        }
        reprise_gbuffer out = output_into(got);
        EXPECT_EQ(reprise_converter_receive(c, &out), REPRISE_NEED_MORE);
    }
    EXPECT_EQ(compared, 5);
    // The frames move 3 px and their camera little: no cut is detected unless reported.
    EXPECT_EQ(cpp.counters().cuts, cut ? 1u : 0u);
    reprise_converter_destroy(c);
}

INSTANTIATE_TEST_SUITE_P(CapiMatchesCpp, CapiConverter, testing::Bool());

TEST(CapiMatchesCpp, StereoEyeIsTheSynthesizers) {
    const Frame left = frames()[1];
    const stereo::EyeCameras eyes = stereo::eye_cameras(left.camera, {}, stereo::Anchor::Left);
    Frame want, got;
    stereo::StereoSynthesizer().synthesize(left, eyes.right, want, {});
    reprise_stereo* s = nullptr;
    ASSERT_EQ(reprise_stereo_create(REPRISE_ABI_VERSION, nullptr, &s), REPRISE_OK);
    const reprise_gbuffer g = gbuffer_of(left);
    reprise_gbuffer out = output_into(got);
    out.motion = {};
    ASSERT_EQ(reprise_stereo_synthesize(s, &g, &out), REPRISE_OK) << reprise_last_error();
    EXPECT_TRUE(test::same_bits(want.color, got.color));
    EXPECT_TRUE(test::same_bits(want.depth, got.depth));
    EXPECT_EQ(0, std::memcmp(&eyes.right.view[0][0], out.camera.view, 64));
    reprise_stereo_destroy(s);
}

// A flag of the synthesizer's options set through the C struct: off, on, and a struct of the
// minor before the field's (ending where it starts), which gets the default (on).
void expect_stereo_flag(const Frame& left, bool stereo::StereoOptions::*flag,
                        int32_t reprise_stereo_options::*field, std::size_t field_offset) {
    const stereo::EyeCameras eyes = stereo::eye_cameras(left.camera, {}, stereo::Anchor::Left);
    Frame want[2];
    for (const bool on : {false, true}) {
        stereo::StereoOptions o;
        o.*flag = on;
        stereo::StereoSynthesizer().synthesize(left, eyes.right, want[on], o);
    }
    ASSERT_FALSE(test::same_bits(want[0].color, want[1].color)) << "the option changes nothing";
    const reprise_gbuffer g = gbuffer_of(left);
    for (const int given : {0, 1, -1}) {  // -1: an older minor's struct, without the field
        reprise_stereo_options options;
        const std::size_t size = given < 0 ? field_offset : sizeof options;
        ASSERT_EQ(reprise_stereo_options_init(&options, size), REPRISE_OK);
        if (given >= 0) options.*field = given;
        reprise_stereo* s = nullptr;
        ASSERT_EQ(reprise_stereo_create(REPRISE_ABI_VERSION, &options, &s), REPRISE_OK)
            << reprise_last_error();
        Frame got;
        reprise_gbuffer out = output_into(got);
        out.motion = {};
        ASSERT_EQ(reprise_stereo_synthesize(s, &g, &out), REPRISE_OK) << reprise_last_error();
        EXPECT_TRUE(test::same_bits(want[given != 0].color, got.color)) << "given " << given;
        reprise_stereo_destroy(s);
    }
}

// widen_silhouettes (minor 2) is the synthesizer's option. The frame has a near square, whose
// edges the option moves.
TEST(CapiMatchesCpp, WidenSilhouettesIsTheSynthesizersOption) {
    Frame left = frames()[1];
    for (int y = 16; y < 32; ++y)
        for (int x = 20; x < 40; ++x) left.depth(x, y) = 1.5f;
    expect_stereo_flag(left, &stereo::StereoOptions::widen_silhouettes,
                       &reprise_stereo_options::widen_silhouettes,
                       offsetof(reprise_stereo_options, widen_silhouettes));
}

// perceptual (minor 3) is the synthesizer's option too.
TEST(CapiMatchesCpp, PerceptualIsTheSynthesizersOption) {
    expect_stereo_flag(frames()[1], &stereo::StereoOptions::perceptual,
                       &reprise_stereo_options::perceptual,
                       offsetof(reprise_stereo_options, perceptual));
}

// perceptual is the converter's option; a minor-2 caller's struct, which ends before it, gets the
// default (on).
TEST(CapiMatchesCpp, PerceptualIsTheConvertersOption) {
    const std::vector<Frame> input = frames();
    std::vector<Frame> want[2];
    for (const bool perceptual : {false, true}) {
        warp::FrameRateConverter converter;
        ASSERT_TRUE(
            warp::FrameRateConverter::create(2, {.perceptual = perceptual}, converter).ok());
        for (const Frame& f : input) {
            ASSERT_TRUE(converter.send(f).ok());
            Frame out;
            while (converter.receive(out)) want[perceptual].push_back(out);
        }
    }
    ASSERT_EQ(want[0].size(), want[1].size());
    ASSERT_FALSE(test::same_bits(want[0][1].color, want[1][1].color))
        << "the option changes nothing";
    for (const int given : {0, 1, -1}) {  // -1: a minor-2 struct, without the field
        reprise_converter_options options;
        const std::size_t size =
            given < 0 ? offsetof(reprise_converter_options, perceptual) : sizeof options;
        ASSERT_EQ(reprise_converter_options_init(&options, size), REPRISE_OK);
        if (given >= 0) options.perceptual = given;
        reprise_converter* c = nullptr;
        ASSERT_EQ(reprise_converter_create(REPRISE_ABI_VERSION, &options, &c), REPRISE_OK)
            << reprise_last_error();
        std::size_t received = 0;
        for (const Frame& f : input) {
            const reprise_gbuffer g = gbuffer_of(f);
            ASSERT_EQ(reprise_converter_send(c, &g), REPRISE_OK) << reprise_last_error();
            for (;;) {
                Frame got;
                reprise_gbuffer out = output_into(got);
                const reprise_status s = reprise_converter_receive(c, &out);
                if (s == REPRISE_NEED_MORE) break;
                ASSERT_EQ(s, REPRISE_OK) << reprise_last_error();
                ASSERT_LT(received, want[0].size());
                EXPECT_TRUE(test::same_bits(want[given != 0][received].color, got.color))
                    << "given " << given << ", output " << received;
                ++received;
            }
        }
        EXPECT_EQ(received, want[0].size());
        reprise_converter_destroy(c);
    }
}

// The C encoder's packet for `frame`, received into a buffer of `capacity` bytes.
void c_packet(reprise_encoder* ce, const Frame& frame, std::size_t capacity,
              std::vector<uint8_t>& bytes) {
    const reprise_gbuffer g = gbuffer_of(frame);
    ASSERT_EQ(reprise_encoder_send_frame(ce, &g), REPRISE_OK) << reprise_last_error();
    bytes.resize(capacity);
    std::size_t size = 0;
    ASSERT_EQ(reprise_encoder_receive_packet(ce, bytes.data(), bytes.size(), &size), REPRISE_OK);
    bytes.resize(size);
}

TEST(CapiMatchesCpp, CodecPacketsAndDecodedFramesAreTheCodecs) {
    const std::vector<Frame> input = frames();
    codec::Encoder encoder;
    codec::Decoder decoder;
    reprise_encoder* ce = nullptr;
    reprise_decoder* cd = nullptr;
    ASSERT_EQ(reprise_encoder_create(REPRISE_ABI_VERSION, nullptr, &ce), REPRISE_OK);
    ASSERT_EQ(reprise_decoder_create(REPRISE_ABI_VERSION, nullptr, &cd), REPRISE_OK);
    for (std::size_t k = 0; k < input.size(); ++k) {
        ASSERT_TRUE(encoder.send_frame(input[k]).ok());
        codec::Packet packet;
        ASSERT_EQ(encoder.receive_packet(packet), Result::Ok);
        std::vector<uint8_t> bytes;
        ASSERT_NO_FATAL_FAILURE(c_packet(ce, input[k], packet.data.size() + 16, bytes));
        EXPECT_EQ(bytes, packet.data) << "packet " << k;

        ASSERT_TRUE(decoder.send_packet(packet.data).ok());
        Frame want, got;
        ASSERT_EQ(decoder.receive_frame(want), Result::Ok);
        ASSERT_EQ(reprise_decoder_send_packet(cd, bytes.data(), bytes.size()), REPRISE_OK);
        reprise_gbuffer out = output_into(got);
        ASSERT_EQ(reprise_decoder_receive_frame(cd, &out), REPRISE_OK) << reprise_last_error();
        EXPECT_TRUE(test::same_bits(want.color, got.color)) << "frame " << k;
        EXPECT_TRUE(test::same_bits(want.depth, got.depth)) << "frame " << k;
        EXPECT_TRUE(test::same_bits(want.motion, got.motion)) << "frame " << k;
        EXPECT_EQ(0, std::memcmp(&want.camera.projection[0][0], out.camera.projection, 64));
    }
    reprise_encoder_destroy(ce);
    reprise_decoder_destroy(cd);
}

// fixed_bounds is the codec's bounds_follow_qp, inverted: at qp 46 the packets are the C++
// encoder's either way, and the stream with fixed bounds is larger (finer depth and motion).
TEST(CapiMatchesCpp, FixedBoundsAreTheCodecsOption) {
    const std::vector<Frame> input = frames();
    std::size_t bytes_of[2] = {0, 0};
    for (const int fixed : {0, 1}) {
        codec::Encoder encoder;
        ASSERT_TRUE(codec::Encoder::create(
                        {.qp = 46, .depth = codec::DepthMode::View, .bounds_follow_qp = fixed == 0},
                        encoder)
                        .ok());
        reprise_encoder_options options;
        ASSERT_EQ(reprise_encoder_options_init(&options, sizeof options), REPRISE_OK);
        EXPECT_EQ(options.fixed_bounds, 0);
        options.qp = 46;
        options.depth = REPRISE_DEPTH_VIEW;
        options.fixed_bounds = fixed;
        reprise_encoder* ce = nullptr;
        ASSERT_EQ(reprise_encoder_create(REPRISE_ABI_VERSION, &options, &ce), REPRISE_OK)
            << reprise_last_error();
        for (std::size_t k = 0; k < input.size(); ++k) {
            ASSERT_TRUE(encoder.send_frame(input[k]).ok());
            codec::Packet packet;
            ASSERT_EQ(encoder.receive_packet(packet), Result::Ok);
            std::vector<uint8_t> bytes;
            ASSERT_NO_FATAL_FAILURE(c_packet(ce, input[k], packet.data.size() + 16, bytes));
            EXPECT_EQ(bytes, packet.data) << "fixed_bounds " << fixed << ", packet " << k;
            bytes_of[fixed] += bytes.size();
        }
        reprise_encoder_destroy(ce);
    }
    EXPECT_LT(bytes_of[0], bytes_of[1]);
    reprise_encoder_options options;
    reprise_encoder_options_init(&options, sizeof options);
    options.fixed_bounds = 2;
    reprise_encoder* ce = nullptr;
    EXPECT_EQ(reprise_encoder_create(REPRISE_ABI_VERSION, &options, &ce),
              REPRISE_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(reprise_last_error()).find("fixed_bounds"), std::string::npos)
        << reprise_last_error();
}

// Colour as 8-bit sRGB display values (ABI 1.4): RGBA8_SRGB into the encoder gives the C++
// encoder's packets from those values, and a decoder made with `display` writes the C++
// decoder's display values; the other calls and a linear decoder refuse the format.
TEST(CapiMatchesCpp, CodecColourAsEightBitSrgbIsTheCodecs) {
    const std::vector<Frame> input = frames();
    codec::Encoder encoder;
    codec::Decoder decoder;
    ASSERT_TRUE(codec::Decoder::create({.display = true}, decoder).ok());
    reprise_encoder* ce = nullptr;
    reprise_decoder* cd = nullptr;
    reprise_decoder_options options;
    ASSERT_EQ(reprise_decoder_options_init(&options, sizeof options), REPRISE_OK);
    EXPECT_EQ(options.display, 0);
    options.display = 1;
    ASSERT_EQ(reprise_encoder_create(REPRISE_ABI_VERSION, nullptr, &ce), REPRISE_OK);
    ASSERT_EQ(reprise_decoder_create(REPRISE_ABI_VERSION, &options, &cd), REPRISE_OK);
    for (std::size_t k = 0; k < input.size(); ++k) {
        Image<glm::u8vec4> shown(kW, kH);
        for (std::size_t p = 0; p < shown.pixel_count(); ++p)
            shown.data()[p] = glm::u8vec4(uint8_t(7 * p + k), uint8_t(p / 3), uint8_t(200 - p), 9);
        ASSERT_TRUE(encoder.send_frame(input[k], shown.view()).ok());
        codec::Packet packet;
        ASSERT_EQ(encoder.receive_packet(packet), Result::Ok);
        reprise_gbuffer g = gbuffer_of(input[k]);
        g.color = image_of(shown, REPRISE_FORMAT_RGBA8_SRGB);
        ASSERT_EQ(reprise_encoder_send_frame(ce, &g), REPRISE_OK) << reprise_last_error();
        std::vector<uint8_t> bytes(packet.data.size());
        std::size_t size = 0;
        ASSERT_EQ(reprise_encoder_receive_packet(ce, bytes.data(), bytes.size(), &size),
                  REPRISE_OK);
        EXPECT_EQ(bytes, packet.data) << "packet " << k;

        ASSERT_TRUE(decoder.send_packet(packet.data).ok());
        codec::DecodedFrame want;
        ASSERT_EQ(decoder.receive_frame(want), Result::Ok);
        ASSERT_EQ(reprise_decoder_send_packet(cd, bytes.data(), bytes.size()), REPRISE_OK);
        Frame got;
        reprise_gbuffer out = output_into(got);
        Image<glm::u8vec4> display(kW, kH);
        if (k == 0) {  // a float colour from a display decoder: refused, the frame kept
            ASSERT_EQ(reprise_decoder_receive_frame(cd, &out), REPRISE_ERROR_INVALID_ARGUMENT);
            EXPECT_NE(std::string(reprise_last_error()).find("RGBA8_SRGB"), std::string::npos)
                << reprise_last_error();
        }
        out.color = image_of(display, REPRISE_FORMAT_RGBA8_SRGB);
        ASSERT_EQ(reprise_decoder_receive_frame(cd, &out), REPRISE_OK) << reprise_last_error();
        EXPECT_EQ(0, std::memcmp(display.data(), want.display.data(),
                                 display.pixel_count() * sizeof(glm::u8vec4)))
            << "frame " << k;
        Image<float> want_depth;
        want_depth.assign(want.depth());
        EXPECT_TRUE(test::same_bits(want_depth, got.depth)) << "frame " << k;
    }
    reprise_encoder_destroy(ce);
    reprise_decoder_destroy(cd);
    // The converter takes linear colour only.
    reprise_converter* c = nullptr;
    ASSERT_EQ(reprise_converter_create(REPRISE_ABI_VERSION, nullptr, &c), REPRISE_OK);
    Image<glm::u8vec4> shown(kW, kH);
    reprise_gbuffer g = gbuffer_of(input[0]);
    g.color = image_of(shown, REPRISE_FORMAT_RGBA8_SRGB);
    EXPECT_EQ(reprise_converter_send(c, &g), REPRISE_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(reprise_last_error()).find("RGBA8_SRGB"), std::string::npos)
        << reprise_last_error();
    reprise_converter_destroy(c);
}

}  // namespace
}  // namespace reprise
