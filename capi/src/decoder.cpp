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
    HeldFrame next;

    void pull() {
        if (!next.held) next.held = decoder->receive_frame(next.frame) == codec::Result::Ok;
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
    return guarded("reprise_decoder_options_init", [&] {
        return init_options("reprise_decoder_options_init", options, struct_size,
                            default_options());
    });
}

reprise_status reprise_decoder_create(uint32_t abi_version, const reprise_decoder_options* given,
                                      reprise_decoder** decoder) {
    const char* function = "reprise_decoder_create";
    return guarded(function, [&] {
        reprise_decoder_options o = default_options();
        REPRISE_CAPI_TRY(check_create(function, abi_version, given, o, decoder));
        REPRISE_CAPI_TRY(check_range(function, "options->max_pixels", double(o.max_pixels), 1.0,
                                     double(kMaxImageSide) * kMaxImageSide));
        auto made = std::make_unique<reprise_decoder>();
        made->decoder = std::make_unique<codec::Decoder>(codec::DecoderOptions{o.max_pixels});
        *decoder = made.release();
        return reprise_status(REPRISE_OK);
    });
}

void reprise_decoder_destroy(reprise_decoder* decoder) { delete decoder; }

reprise_status reprise_decoder_send_packet(reprise_decoder* decoder, const uint8_t* data,
                                           size_t size) {
    const char* function = "reprise_decoder_send_packet";
    return guarded(function, [&] {
        REPRISE_CAPI_TRY(check_pointer(function, decoder, "decoder"));
        if (!data && size > 0)
            return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                        "data is NULL with size " + std::to_string(size));
        const Status status = decoder->decoder->send_packet(std::span<const uint8_t>(data, size));
        if (!status) return fail(REPRISE_ERROR_INVALID_DATA, function, status.message());
        return reprise_status(REPRISE_OK);
    });
}

reprise_status reprise_decoder_flush(reprise_decoder* decoder) {
    const char* function = "reprise_decoder_flush";
    return guarded(function, [&] {
        REPRISE_CAPI_TRY(check_pointer(function, decoder, "decoder"));
        decoder->decoder->flush();
        return reprise_status(REPRISE_OK);
    });
}

reprise_status reprise_decoder_output_size(reprise_decoder* decoder, int32_t* width,
                                           int32_t* height) {
    const char* function = "reprise_decoder_output_size";
    return guarded(function, [&] {
        REPRISE_CAPI_TRY(check_pointer(function, decoder, "decoder"));
        decoder->pull();
        return held_size(function, decoder->next, width, height);
    });
}

reprise_status reprise_decoder_receive_frame(reprise_decoder* decoder, reprise_gbuffer* out) {
    const char* function = "reprise_decoder_receive_frame";
    return guarded(function, [&] {
        REPRISE_CAPI_TRY(check_pointer(function, decoder, "decoder"));
        decoder->pull();
        return receive_held(function, decoder->next, kColor | kDepth | kMotion, out);
    });
}

}  // extern "C"
