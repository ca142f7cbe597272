#include "synthesized_views.hpp"

#include "reprise/stereo/rig.hpp"
#include "reprise/warp/extrapolate.hpp"

namespace reprise::cli {

namespace {

constexpr float kIpd = 0.064f;
constexpr int kDisplayPerFrame = 4;  // 120 Hz from 30 Hz

double display_psnr(const Frame& truth, const Frame& made, Image<glm::vec3>& a,
                    Image<glm::vec3>& b) {
    a.resize(truth.width(), truth.height());
    b.resize(made.width(), made.height());
    to_display(truth.color.view(), a.view());
    to_display(made.color.view(), b.view());
    return std::min(psnr(a.view(), b.view()), 60.0);
}

}  // namespace

const char* SynthesizedViews::name(int view) {
    static const char* names[kViews] = {"+1/4 frame", "+2/4 frame", "+3/4 frame", "other eye"};
    return names[view];
}

SynthesizedViewScorer::SynthesizedViewScorer(server::Renderer& renderer, const server::Scene& scene,
                                             const server::CameraPath& path, double fps)
    : renderer_(renderer), scene_(scene), path_(path), fps_(fps) {}

Status SynthesizedViewScorer::add(int index, const Frame& rendered, const GBufferView& decoded,
                                  SynthesizedViews& views) {
    const int w = rendered.width(), h = rendered.height();
    const server::RenderSettings settings{.width = w, .height = h};
    // The same decoded colour with the renderer's own depth and motion.
    lossless_.assign(decoded);
    lossless_.depth = rendered.depth;
    lossless_.motion = rendered.motion;
    warp::PoseExtrapolator extrapolator;
    Image<glm::vec3> a, b;
    for (int v = 0; v < SynthesizedViews::kViews; ++v) {
        const bool eye = v == SynthesizedViews::kViews - 1;
        const float periods = eye ? 0.0f : float(v + 1) / kDisplayPerFrame;
        const double time = (index + double(periods)) / fps_;
        server::Instant at = server::instant_on_path(path_, scene_, time, w, h);
        const server::Instant before =
            server::instant_on_path(path_, scene_, time - 1.0 / fps_, w, h);
        if (eye) {
            const stereo::EyeCameras eyes =
                stereo::eye_cameras(rendered.camera, {.ipd = kIpd}, stereo::Anchor::Left);
            at.view = eyes.right.view;
            at.projection = eyes.right.projection;
        }
        REPRISE_TRY(renderer_.render(scene_, at, before, settings, truth_));
        REPRISE_TRY(extrapolator.extrapolate(decoded, at.view, at.projection, periods, warped_));
        views.decoded_psnr[v] += display_psnr(truth_, warped_, a, b);
        REPRISE_TRY(extrapolator.extrapolate(lossless_, at.view, at.projection, periods, warped_));
        views.rendered_psnr[v] += display_psnr(truth_, warped_, a, b);
    }
    ++views.frames;
    return {};
}

}  // namespace reprise::cli
