#pragma once
// Peers of frame-rate upconversion, run on the same display frames as reprise's own methods:
// ffmpeg's minterpolate filter, OpenCV DIS optical flow with remap, OpenCV Telea inpainting.
#include <memory>
#include <string>
#include <vector>

#include "reprise/core/frame.hpp"
#include "reprise/core/visualize.hpp"

namespace reprise::cli {

// True when `ffmpeg` runs and has the minterpolate filter.
bool ffmpeg_has_minterpolate(const std::string& ffmpeg = "ffmpeg");

// Upconverts by `factor` with ffmpeg's motion-compensated interpolation (minterpolate,
// mi_mode=mci): output frame j shows instant j / (factor * input rate), (n - 1) * factor + 1
// frames. The input goes through a raw RGB file in `scratch_dir`; `seconds` is the whole
// ffmpeg run: process start, decoding the raw input, colour conversions and the filter.
Status ffmpeg_minterpolate(const std::vector<Image<Rgb8>>& input, int factor,
                           const std::string& scratch_dir, std::vector<Image<Rgb8>>& output,
                           double& seconds, const std::string& ffmpeg = "ffmpeg");

// OpenCV's dense inverse search flow (preset MEDIUM) on grey levels, both ways between two
// frames; an in-between frame warps both backwards along the scaled flow and blends them.
class DisInterpolator {
public:
    DisInterpolator();
    ~DisInterpolator();
    void set_pair(ImageView<const Rgb8> a, ImageView<const Rgb8> b);
    // The frame at fraction s in (0, 1) from a to b, same size as the pair.
    void interpolate(float s, ImageView<Rgb8> out);

private:
    struct State;
    std::unique_ptr<State> state_;
};

// Fills the pixels where `holes` is nonzero by OpenCV's Telea inpainting (radius 3) of the
// display values rounded to 8 bits; other pixels keep their exact values.
void inpaint_telea(ImageView<glm::vec3> display, ImageView<const uint8_t> holes);

// The plain use of rendered vectors that anyone could write: a and b splatted one pixel each to
// instant s in (0, 1) (a along its backward motion negated, b along its own), the nearer surface
// winning, the two blended where they land within 2 % in depth, holes by Telea inpainting;
// display values out.
class RenderedVectorsInterpolator {
public:
    void interpolate(const Frame& a, const Frame& b, float s, Image<glm::vec3>& display);

private:
    Image<glm::vec3> color_[2];
    Image<float> depth_[2];
    Image<uint8_t> covered_[2], holes_;
};

}  // namespace reprise::cli
