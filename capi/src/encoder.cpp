// reprise_encoder: codec::Encoder behind the C interface (reprise.h).
#include <cstring>
#include <memory>

#include "gbuffer.hpp"
#include "plumbing.hpp"
#include "reprise/codec/codec.hpp"

using namespace reprise;
using namespace reprise::capi;

struct reprise_encoder {
    std::unique_ptr<codec::Encoder> encoder;
    Frame input;
    Image<glm::u8vec4> display;  // the colour given as RGBA8_SRGB
    codec::Packet packet;
    bool held = false;  // `packet` was pulled (its size told) and not yet copied out
};

namespace {

reprise_encoder_options default_options() {
    const codec::EncoderOptions d;
    reprise_encoder_options o{};
    o.qp = d.qp;
    o.bitrate_kbps = d.bitrate_kbps;
    o.keyint = d.keyint;
    o.fps = d.fps;
    o.chroma444 = d.chroma == codec::Chroma::C444;
    o.depth = int32_t(d.depth);
    o.depth_error = d.depth_error;
    o.view_error_px = d.view_error_px;
    o.view_displacement = d.view_displacement;
    o.motion_error_px = d.motion_error_px;
    o.skip_threshold = d.skip_threshold;
    o.detect_cuts = d.detect_cuts;
    o.fit_cameras = d.fit_cameras;
    o.fixed_bounds = !d.bounds_follow_qp;
    return o;
}

reprise_status to_encoder_options(const char* function, const reprise_encoder_options& o,
                                  codec::EncoderOptions& e) {
    REPRISE_CAPI_TRY(check_range(function, "options->qp", o.qp, 0, 51));
    REPRISE_CAPI_TRY(check_range(function, "options->bitrate_kbps", o.bitrate_kbps, 0, 1e7));
    REPRISE_CAPI_TRY(check_range(function, "options->keyint", o.keyint, 0, 1e6));
    REPRISE_CAPI_TRY(check_range(function, "options->fps", o.fps, 1e-3, 1e4));
    REPRISE_CAPI_TRY(check_flag(function, "options->chroma444", o.chroma444));
    REPRISE_CAPI_TRY(check_range(function, "options->depth", o.depth, 0, 3));
    REPRISE_CAPI_TRY(check_range(function, "options->depth_error", o.depth_error, 1e-7, 1.0));
    REPRISE_CAPI_TRY(check_range(function, "options->view_error_px", o.view_error_px, 1e-3, 64.0));
    REPRISE_CAPI_TRY(
        check_range(function, "options->view_displacement", o.view_displacement, 1e-6, 1e6));
    if (o.motion_error_px != 0.0f)
        REPRISE_CAPI_TRY(
            check_range(function, "options->motion_error_px", o.motion_error_px, 0.1, 8.0));
    REPRISE_CAPI_TRY(check_range(function, "options->skip_threshold", o.skip_threshold, 0, 255));
    REPRISE_CAPI_TRY(check_flag(function, "options->detect_cuts", o.detect_cuts));
    REPRISE_CAPI_TRY(check_flag(function, "options->fit_cameras", o.fit_cameras));
    REPRISE_CAPI_TRY(check_flag(function, "options->fixed_bounds", o.fixed_bounds));
    e.qp = o.qp;
    e.bitrate_kbps = o.bitrate_kbps;
    e.keyint = o.keyint;
    e.fps = o.fps;
    e.chroma = o.chroma444 ? codec::Chroma::C444 : codec::Chroma::C420;
    e.depth = codec::DepthMode(o.depth);
    e.depth_error = o.depth_error;
    e.view_error_px = o.view_error_px;
    e.view_displacement = o.view_displacement;
    e.motion_error_px = o.motion_error_px;
    e.skip_threshold = o.skip_threshold;
    e.detect_cuts = o.detect_cuts != 0;
    e.fit_cameras = o.fit_cameras != 0;
    e.bounds_follow_qp = o.fixed_bounds == 0;
    return REPRISE_OK;
}

}  // namespace

extern "C" {

reprise_status reprise_encoder_options_init(reprise_encoder_options* options, size_t struct_size) {
    return init_options("reprise_encoder_options_init", options, struct_size, default_options());
}

reprise_status reprise_encoder_create(uint32_t abi_version, const reprise_encoder_options* given,
                                      reprise_encoder** encoder) {
    const char* function = "reprise_encoder_create";
    return create_handle(function, abi_version, given, default_options(), encoder,
                         [&](const reprise_encoder_options& o, reprise_encoder& made) {
                             codec::EncoderOptions options;
                             REPRISE_CAPI_TRY(to_encoder_options(function, o, options));
                             made.encoder = std::make_unique<codec::Encoder>();
                             const Status status = codec::Encoder::create(options, *made.encoder);
                             if (!status)
                                 return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                                             status.message());
                             return reprise_status(REPRISE_OK);
                         });
}

void reprise_encoder_destroy(reprise_encoder* encoder) { delete encoder; }

reprise_status reprise_encoder_send_frame(reprise_encoder* encoder, const reprise_gbuffer* frame) {
    const char* function = "reprise_encoder_send_frame";
    return with_handle(function, encoder, "encoder", [&](reprise_encoder& e) {
        REPRISE_CAPI_TRY(
            read_gbuffer(function, "frame", frame, kColor | kDepth | kMotion, e.input, &e.display));
        const Status status = e.display.empty() ? e.encoder->send_frame(e.input)
                                                : e.encoder->send_frame(e.input, e.display.view());
        if (!status) return fail(REPRISE_ERROR_INVALID_ARGUMENT, function, status.message());
        return reprise_status(REPRISE_OK);
    });
}

reprise_status reprise_encoder_receive_packet(reprise_encoder* encoder, uint8_t* data,
                                              size_t capacity, size_t* size) {
    const char* function = "reprise_encoder_receive_packet";
    return with_handle(function, encoder, "encoder", [&](reprise_encoder& e) {
        REPRISE_CAPI_TRY(check_pointer(function, size, "size"));
        *size = 0;
        if (!e.held) {
            if (!e.encoder->receive_packet(e.packet)) return reprise_status(REPRISE_NEED_MORE);
            e.held = true;
        }
        const std::vector<uint8_t>& bytes = e.packet.data;
        *size = bytes.size();
        if (!data || capacity < bytes.size())
            return fail(REPRISE_ERROR_BUFFER_TOO_SMALL, function,
                        "the packet has " + std::to_string(bytes.size()) + " bytes, capacity is " +
                            std::to_string(data ? capacity : 0) + " (the packet is kept)");
        std::memcpy(data, bytes.data(), bytes.size());
        e.held = false;
        return reprise_status(REPRISE_OK);
    });
}

reprise_status reprise_encoder_flush(reprise_encoder* encoder) {
    return with_handle("reprise_encoder_flush", encoder, "encoder", [&](reprise_encoder& e) {
        e.encoder->flush();
        return REPRISE_OK;
    });
}

}  // extern "C"
