// reprise_decoder: codec::Decoder behind the C interface (reprise.h).
#include <memory>
#include <span>

#include "gbuffer.hpp"
#include "plumbing.hpp"
#include "reprise/codec/codec.hpp"

using namespace reprise;
using namespace reprise::capi;

struct reprise_decoder {
    std::unique_ptr<codec::Decoder> decoder;
    bool display = false;  // colour out as RGBA8_SRGB
    HeldFrame next;
    codec::DecodedFrame decoded;

    void pull() {
        if (next.held) return;
        if (!display) {
            next.held = decoder->receive_frame(next.frame) == Result::Ok;
            return;
        }
        next.held = decoder->receive_frame(decoded) == Result::Ok;
        if (!next.held) return;
        std::swap(next.display, decoded.display);  // buffers go back and forth, not reallocated
        next.frame.color.clear();
        next.frame.depth.assign(decoded.depth());
        next.frame.motion.assign(decoded.motion());
        next.frame.camera = decoded.camera;
        next.frame.fps = decoded.fps;
        decoded.release();
    }
};

namespace {

reprise_decoder_options default_options() {
    reprise_decoder_options o{};
    o.max_pixels = codec::DecoderOptions{}.max_pixels;
    return o;
}

}  // namespace

extern "C" {

reprise_status reprise_decoder_options_init(reprise_decoder_options* options, size_t struct_size) {
    return init_options("reprise_decoder_options_init", options, struct_size, default_options());
}

reprise_status reprise_decoder_create(uint32_t abi_version, const reprise_decoder_options* given,
                                      reprise_decoder** decoder) {
    const char* function = "reprise_decoder_create";
    return create_handle(
        function, abi_version, given, default_options(), decoder,
        [&](const reprise_decoder_options& o, reprise_decoder& made) {
            REPRISE_CAPI_TRY(check_range(function, "options->max_pixels", double(o.max_pixels), 1.0,
                                         double(kMaxImageSide) * kMaxImageSide));
            // A caller of an older minor had `reserved` there, never read: not read now either.
            const bool has_display = (abi_version & 0xFFFFu) >= 4;
            if (has_display) REPRISE_CAPI_TRY(check_flag(function, "options->display", o.display));
            made.display = has_display && o.display != 0;
            made.decoder = std::make_unique<codec::Decoder>();
            const Status status = codec::Decoder::create(
                {.max_pixels = o.max_pixels, .display = made.display}, *made.decoder);
            if (!status) return fail(REPRISE_ERROR_INVALID_ARGUMENT, function, status.message());
            return reprise_status(REPRISE_OK);
        });
}

void reprise_decoder_destroy(reprise_decoder* decoder) { delete decoder; }

reprise_status reprise_decoder_send_packet(reprise_decoder* decoder, const uint8_t* data,
                                           size_t size) {
    const char* function = "reprise_decoder_send_packet";
    return with_handle(function, decoder, "decoder", [&](reprise_decoder& d) {
        if (!data && size > 0)
            return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                        "data is NULL with size " + std::to_string(size));
        const Status status = d.decoder->send_packet(std::span<const uint8_t>(data, size));
        if (!status) return fail(REPRISE_ERROR_INVALID_DATA, function, status.message());
        return reprise_status(REPRISE_OK);
    });
}

reprise_status reprise_decoder_flush(reprise_decoder* decoder) {
    return with_handle("reprise_decoder_flush", decoder, "decoder", [&](reprise_decoder& d) {
        d.decoder->flush();
        return REPRISE_OK;
    });
}

reprise_status reprise_decoder_output_size(reprise_decoder* decoder, int32_t* width,
                                           int32_t* height) {
    const char* function = "reprise_decoder_output_size";
    return with_handle(function, decoder, "decoder", [&](reprise_decoder& d) {
        d.pull();
        return held_size(function, d.next, width, height);
    });
}

reprise_status reprise_decoder_receive_frame(reprise_decoder* decoder, reprise_gbuffer* out) {
    const char* function = "reprise_decoder_receive_frame";
    return with_handle(function, decoder, "decoder", [&](reprise_decoder& d) {
        d.pull();
        return receive_held(function, d.next, kColor | kDepth | kMotion, out);
    });
}

}  // extern "C"
