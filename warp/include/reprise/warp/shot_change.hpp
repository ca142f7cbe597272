// The shot-change test of FrameRateConverter for a frame whose camera does not say whether a cut
// came before it (FrucOptions::cut_misses, cut_color), as a function of its own so that a GPU
// can repeat it and decide alike.
#pragma once

#include <cstdint>

#include "reprise/core/gbuffer.hpp"
#include "reprise/core/image.hpp"
#include "reprise/warp/reproject.hpp"

namespace reprise::warp {

// The survey: `frame` reprojected into `previous` on every 4th pixel of every 4th row, depth
// tolerance 5 %.
inline constexpr int kShotChangeStep = 4;
inline constexpr float kShotChangeDepthTolerance = 0.05f;

struct ShotChange {
    bool cut = false;
    ReprojectCounts counts;   // of the looked-up pixels
    uint64_t difference = 0;  // display_difference summed over the hits
};

// A pixel's difference in display colour: each channel (R, G, B) clamped to [0, 1], encoded as
// sRGB (a 1025-entry table, linearly interpolated: display_table), |a - b| rounded to units of
// 2^-20, the three added. Integers, so any order of summing gives the same total.
uint32_t display_difference(const glm::vec4& a, const glm::vec4& b);
// The table display_difference encodes through: sRGB of i / 1024 for i in 0..1024.
const float* display_table();
inline constexpr int kDisplayTableSize = 1024;

// The decision from the survey's counts and summed difference over a width x height frame: a cut
// when the misses (behind, occluded, other id, invalid; off-screen when nothing hit) exceed
// `cut_misses` of the looked-up pixels, or the hits' mean difference per channel exceeds
// `cut_color`.
bool shot_change_decision(const ReprojectCounts& counts, uint64_t difference, int width, int height,
                          float cut_misses, float cut_color);

struct ShotChangeScratch {
    Image<glm::vec4> reprojected;
    Image<uint8_t> hit;
};

// The whole test on the CPU. Frames without depth or motion, or a previous frame without depth,
// are never a cut.
ShotChange shot_change(const GBufferView& frame, const GBufferView& previous, float cut_misses,
                       float cut_color, ShotChangeScratch& scratch);

}  // namespace reprise::warp
