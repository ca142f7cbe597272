// reprise_converter: warp::FrameRateConverter behind the C interface (reprise.h).
#include <deque>
#include <memory>
#include <utility>

#include "gbuffer.hpp"
#include "plumbing.hpp"
#include "reprise/warp/fruc.hpp"

using namespace reprise;
using namespace reprise::capi;

struct reprise_converter {
    int factor = 2;
    warp::FrucOptions options;
    std::unique_ptr<warp::FrameRateConverter> fruc;
    std::deque<Frame> flushed;  // outputs of a sequence ended by flush, not yet received
    Frame input;                // the caller's frame in float layout, lent to the converter
    HeldFrame next;

    // Holds the next output if there is one.
    bool pull() {
        if (next.held) return true;
        if (!flushed.empty()) {
            std::swap(next.frame, flushed.front());
            flushed.pop_front();
            next.held = true;
        } else {
            next.held = fruc->receive(next.frame).ok();
        }
        return next.held;
    }
};

namespace {

constexpr unsigned kConverterReads = kColor | kDepth | kMotion | kUi;
constexpr unsigned kConverterWrites = kColor | kDepth | kMotion | kUi;

reprise_status to_fruc_options(const char* function, const reprise_converter_options& o,
                               warp::FrucOptions& fruc) {
    REPRISE_CAPI_TRY(check_range(function, "options->factor", o.factor, 1, 16));
    REPRISE_CAPI_TRY(check_range(function, "options->mode", o.mode, 0, 1));
    REPRISE_CAPI_TRY(check_range(function, "options->warp", o.warp, 0, 3));
    REPRISE_CAPI_TRY(check_range(function, "options->fill", o.fill, 0, 4));
    REPRISE_CAPI_TRY(check_flag(function, "options->refine", o.refine));
    REPRISE_CAPI_TRY(check_range(function, "options->budget_db", o.budget_db, 0.0, 100.0));
    REPRISE_CAPI_TRY(check_flag(function, "options->composite_ui", o.composite_ui));
    REPRISE_CAPI_TRY(check_flag(function, "options->widen_silhouettes", o.widen_silhouettes));
    REPRISE_CAPI_TRY(check_flag(function, "options->perceptual", o.perceptual));
    constexpr warp::WarpMethod warps[] = {warp::WarpMethod::Grid, warp::WarpMethod::Reverse,
                                          warp::WarpMethod::Splat, warp::WarpMethod::Auto};
    constexpr warp::FillMethod fills[] = {warp::FillMethod::PullPush, warp::FillMethod::None,
                                          warp::FillMethod::Andreev, warp::FillMethod::Auto,
                                          warp::FillMethod::Patch};
    fruc.mode = o.mode == REPRISE_FRUC_EXTRAPOLATE ? warp::FrucMode::Extrapolate
                                                   : warp::FrucMode::Interpolate;
    fruc.warp = warps[o.warp];
    fruc.fill = fills[o.fill];
    fruc.refine.enabled = o.refine != 0;
    fruc.auto_choice.budget_db = o.budget_db;
    fruc.composite_ui = o.composite_ui != 0;
    fruc.widen_silhouettes = o.widen_silhouettes != 0;
    fruc.perceptual = o.perceptual != 0;
    return REPRISE_OK;
}

// A new converter with c's factor and options (checked again by the library: its message).
reprise_status make_converter(const char* function, reprise_converter& c) {
    const Status made = warp::FrameRateConverter::create(c.factor, c.options, *c.fruc);
    if (!made) return fail(REPRISE_ERROR_INVALID_ARGUMENT, function, made.message());
    return REPRISE_OK;
}

reprise_converter_options default_options() {
    reprise_converter_options o{};
    o.factor = 2;
    o.mode = REPRISE_FRUC_INTERPOLATE;
    o.warp = REPRISE_WARP_GRID;
    o.fill = REPRISE_FILL_PULLPUSH;
    o.refine = 1;
    o.widen_silhouettes = 1;
    o.perceptual = 1;
    return o;
}

}  // namespace

extern "C" {

reprise_status reprise_converter_options_init(reprise_converter_options* options,
                                              size_t struct_size) {
    return init_options("reprise_converter_options_init", options, struct_size, default_options());
}

reprise_status reprise_converter_create(uint32_t abi_version,
                                        const reprise_converter_options* given,
                                        reprise_converter** converter) {
    const char* function = "reprise_converter_create";
    return create_handle(function, abi_version, given, default_options(), converter,
                         [&](const reprise_converter_options& o, reprise_converter& made) {
                             REPRISE_CAPI_TRY(to_fruc_options(function, o, made.options));
                             made.factor = o.factor;
                             made.fruc = std::make_unique<warp::FrameRateConverter>();
                             return make_converter(function, made);
                         });
}

void reprise_converter_destroy(reprise_converter* converter) { delete converter; }

reprise_status reprise_converter_send(reprise_converter* converter, const reprise_gbuffer* frame) {
    const char* function = "reprise_converter_send";
    return with_handle(function, converter, "converter", [&](reprise_converter& c) {
        REPRISE_CAPI_TRY(read_gbuffer(function, "frame", frame, kConverterReads, c.input));
        const Status status = c.fruc->send(std::move(c.input));
        if (!status) return fail(REPRISE_ERROR_INVALID_ARGUMENT, function, status.message());
        return reprise_status(REPRISE_OK);
    });
}

reprise_status reprise_converter_flush(reprise_converter* converter) {
    const char* function = "reprise_converter_flush";
    return with_handle(function, converter, "converter", [&](reprise_converter& c) {
        Frame out;
        while (c.fruc->receive(out)) c.flushed.push_back(std::move(out));
        c.fruc = std::make_unique<warp::FrameRateConverter>();
        return make_converter(function, c);
    });
}

reprise_status reprise_converter_output_size(reprise_converter* converter, int32_t* width,
                                             int32_t* height) {
    const char* function = "reprise_converter_output_size";
    return with_handle(function, converter, "converter", [&](reprise_converter& c) {
        c.pull();
        return held_size(function, c.next, width, height);
    });
}

reprise_status reprise_converter_receive(reprise_converter* converter, reprise_gbuffer* out) {
    const char* function = "reprise_converter_receive";
    return with_handle(function, converter, "converter", [&](reprise_converter& c) {
        c.pull();
        return receive_held(function, c.next, kConverterWrites, out);
    });
}

}  // extern "C"
