#pragma once
// Stereo camera rigs: the two eyes' cameras around one camera, and disparity from depth.
//
// Sign convention: for a point at depth z, x_right = x_left - d with
//     d = f * ipd * (1/z - 1/convergence)   pixels, f = projection[0][0] * width / 2,
// so content in front of the convergence distance (negative parallax) shifts left in the right
// eye, content behind it right. A parallel rig converges at infinity (1/convergence = 0).
#include "reprise/core/frame.hpp"

namespace reprise::stereo {

enum class Rig {
    Parallel,  // both eyes keep the symmetric projection: zero disparity only at infinity
    OffAxis,   // asymmetric frusta whose centres converge at `convergence` (zero disparity there)
};

struct StereoRig {
    float ipd = 0.064f;         // eye separation, scene units
    float convergence = 10.0f;  // zero-disparity distance (OffAxis), scene units
    Rig rig = Rig::Parallel;
};

enum class Eye { Left, Right };
// Where the given camera sits in the rig.
enum class Anchor { Centre, Left, Right };

struct EyeCameras {
    Camera left, right;
    const Camera& operator[](Eye e) const { return e == Eye::Left ? left : right; }
};

// Anchor::Centre: the eyes sit at -ipd/2 and +ipd/2 along the camera's x axis (the previous
// views are offset the same way); OffAxis shifts each eye's projection centre by
// f * (eye offset) / convergence so that the frusta meet at the convergence plane.
// Anchor::Left/Right: `camera` is that eye, returned unchanged; the other eye is one ipd to its
// right/left, its projection centre shifted by f * ipd / convergence (OffAxis) relative to it,
// so that the disparity between the pair is d above either way.
EyeCameras eye_cameras(const Camera& camera, const StereoRig& rig, Anchor anchor = Anchor::Centre);

// d above, in pixels, for a camera with `projection` rendering an image `width` pixels wide.
float disparity_px(const StereoRig& rig, const glm::mat4& projection, int width, float depth);

// Which eye to render this frame from the camera's own motion (view vs prev_view). Moving right,
// render the right (leading) eye: the synthesized left eye then stands where the rendered right
// eyes of the previous frames stood, so the history holds what it must invent (its
// disocclusions lie on the side the leading eye has already seen). Moving left, render the left
// eye. Sideways motion below `dead_zone` * ipd per frame keeps `previous` (no flicker).
Eye choose_rendered_eye(const Camera& camera, const StereoRig& rig, Eye previous = Eye::Left,
                        float dead_zone = 0.05f);

inline Eye other(Eye e) { return e == Eye::Left ? Eye::Right : Eye::Left; }

}  // namespace reprise::stereo
