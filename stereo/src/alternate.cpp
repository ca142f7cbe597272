// Temporal eye alternation: the other eye from this frame's rendered eye and that eye's history.
#include "reprise/stereo/alternate.hpp"

namespace reprise::stereo {

StereoStats EyeAlternation::next(const GBufferView& rendered, Eye eye, const Camera& target,
                                 Frame& out, const StereoOptions& options) {
    const int made = int(other(eye)), kept = int(eye);
    if (rendered.camera.cut == Cut::Yes) reset();
    const Frame* history = kept_[made] ? &history_[made] : nullptr;
    const StereoStats stats = synthesizer_.synthesize(rendered, target, out, options, history);
    Frame& h = history_[kept];
    h.color.assign(rendered.color);
    h.depth.assign(rendered.depth);
    h.motion.assign(rendered.motion);
    h.camera = rendered.camera;
    kept_[kept] = true;
    return stats;
}

}  // namespace reprise::stereo
