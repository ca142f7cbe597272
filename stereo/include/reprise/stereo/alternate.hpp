#pragma once
// Temporal eye alternation (Didyk et al. 2010): each frame renders one eye, the two taking turns,
// and synthesizes the other from it, with the last rendered frame of that eye (one frame old
// when they alternate) warped to the target to fill what the rendered eye does not see. About
// half the render cost of a stereo pair.
#include "reprise/stereo/rig.hpp"
#include "reprise/stereo/synthesize.hpp"

namespace reprise::stereo {

class EyeAlternation {
public:
    // The eye to render at frame `index`: left on even frames, right on odd ones.
    static Eye rendered_eye(long long index) { return index % 2 == 0 ? Eye::Left : Eye::Right; }

    // `rendered` is eye `eye` of this frame (colour, depth, camera); makes the other eye, seen
    // from `target`, into `out` with the kept frame of that eye as history (none before one is
    // kept, and none across a shot change: rendered.camera.cut). Keeps a copy of `rendered`'s
    // colour, depth, motion and camera as the history of its eye.
    StereoStats next(const GBufferView& rendered, Eye eye, const Camera& target, Frame& out,
                     const StereoOptions& options = {});
    // Forgets both histories (a seek).
    void reset() { kept_[0] = kept_[1] = false; }

private:
    StereoSynthesizer synthesizer_;
    Frame history_[2];  // per eye (Eye as index): colour, depth, motion and camera
    bool kept_[2] = {false, false};
};

}  // namespace reprise::stereo
