// reprise_stereo: stereo::StereoSynthesizer behind the C interface (reprise.h).
#include <memory>
#include <utility>

#include "gbuffer.hpp"
#include "plumbing.hpp"
#include "reprise/stereo/rig.hpp"
#include "reprise/stereo/synthesize.hpp"

using namespace reprise;
using namespace reprise::capi;

struct reprise_stereo {
    stereo::StereoOptions options;
    stereo::StereoRig rig;
    stereo::Eye rendered = stereo::Eye::Left;
    bool temporal = false;
    stereo::StereoSynthesizer synthesizer;
    Frame input, previous, made;
    bool has_previous = false;
};

namespace {

reprise_stereo_options default_options() {
    reprise_stereo_options o{};
    o.ipd = 0.064f;
    o.convergence = 10.0f;
    o.rig = REPRISE_RIG_PARALLEL;
    o.rendered_eye = REPRISE_EYE_LEFT;
    o.warp = REPRISE_WARP_GRID;
    o.fill = REPRISE_FILL_PULLPUSH;
    o.widen_silhouettes = 1;
    o.perceptual = 1;
    return o;
}

reprise_status configure(const char* function, const reprise_stereo_options& o, reprise_stereo& s) {
    REPRISE_CAPI_TRY(check_range(function, "options->ipd", o.ipd, 1e-6, 1e6));
    REPRISE_CAPI_TRY(check_range(function, "options->convergence", o.convergence, 1e-6, 1e9));
    REPRISE_CAPI_TRY(check_range(function, "options->rig", o.rig, 0, 1));
    REPRISE_CAPI_TRY(check_range(function, "options->rendered_eye", o.rendered_eye, 0, 1));
    if (o.warp != REPRISE_WARP_GRID && o.warp != REPRISE_WARP_SPLAT)
        return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                    "options->warp " + std::to_string(o.warp) +
                        " is neither REPRISE_WARP_GRID nor REPRISE_WARP_SPLAT");
    REPRISE_CAPI_TRY(check_range(function, "options->fill", o.fill, 0, 4));
    if (o.fill == REPRISE_FILL_AUTO)
        return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                    "options->fill REPRISE_FILL_AUTO: the eye has no automatic fill");
    REPRISE_CAPI_TRY(check_flag(function, "options->temporal", o.temporal));
    REPRISE_CAPI_TRY(check_flag(function, "options->widen_silhouettes", o.widen_silhouettes));
    REPRISE_CAPI_TRY(check_flag(function, "options->perceptual", o.perceptual));
    constexpr stereo::StereoFill fills[] = {stereo::StereoFill::PullPush, stereo::StereoFill::None,
                                            stereo::StereoFill::Andreev, stereo::StereoFill::None,
                                            stereo::StereoFill::Patch};
    s.rig = {.ipd = o.ipd,
             .convergence = o.convergence,
             .rig = o.rig == REPRISE_RIG_OFF_AXIS ? stereo::Rig::OffAxis : stereo::Rig::Parallel};
    s.rendered = o.rendered_eye == REPRISE_EYE_RIGHT ? stereo::Eye::Right : stereo::Eye::Left;
    s.options.warp =
        o.warp == REPRISE_WARP_SPLAT ? stereo::StereoWarp::Splat : stereo::StereoWarp::Grid;
    s.options.fill = fills[o.fill];
    s.temporal = o.temporal != 0;
    s.options.widen_silhouettes = o.widen_silhouettes != 0;
    s.options.perceptual = o.perceptual != 0;
    return REPRISE_OK;
}

}  // namespace

extern "C" {

reprise_status reprise_stereo_options_init(reprise_stereo_options* options, size_t struct_size) {
    return init_options("reprise_stereo_options_init", options, struct_size, default_options());
}

reprise_status reprise_stereo_create(uint32_t abi_version, const reprise_stereo_options* given,
                                     reprise_stereo** stereo) {
    const char* function = "reprise_stereo_create";
    return create_handle(function, abi_version, given, default_options(), stereo,
                         [&](const reprise_stereo_options& o, reprise_stereo& made) {
                             return configure(function, o, made);
                         });
}

void reprise_stereo_destroy(reprise_stereo* stereo) { delete stereo; }

reprise_status reprise_stereo_synthesize(reprise_stereo* stereo, const reprise_gbuffer* rendered,
                                         reprise_gbuffer* eye) {
    const char* function = "reprise_stereo_synthesize";
    return with_handle(function, stereo, "stereo", [&](reprise_stereo& s) {
        Frame& input = s.input;
        REPRISE_CAPI_TRY(
            read_gbuffer(function, "rendered", rendered, kColor | kDepth | kMotion, input));
        if (input.depth.empty())
            return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                        "rendered->depth.data is NULL: the other eye needs depth");
        if (!rendered->camera.valid || !has_projection(input.camera))
            return fail(REPRISE_ERROR_INVALID_ARGUMENT, function,
                        "rendered->camera is not valid: disparity needs the projection");
        REPRISE_CAPI_TRY(
            check_output(function, eye, input.width(), input.height(), kColor | kDepth));
        if (input.camera.cut == Cut::Yes) s.has_previous = false;
        const stereo::EyeCameras eyes = stereo::eye_cameras(
            input.camera, s.rig,
            s.rendered == stereo::Eye::Left ? stereo::Anchor::Left : stereo::Anchor::Right);
        const Camera& target = eyes[stereo::other(s.rendered)];
        const bool history = s.temporal && s.has_previous && s.previous.width() == input.width() &&
                             s.previous.height() == input.height();
        s.synthesizer.synthesize(input, target, s.made, s.options, history ? &s.previous : nullptr);
        s.made.fps = input.fps;
        REPRISE_CAPI_TRY(write_gbuffer(function, s.made, eye));
        if (s.temporal) {
            std::swap(s.previous, s.input);
            s.has_previous = true;
        }
        return reprise_status(REPRISE_OK);
    });
}

}  // extern "C"
