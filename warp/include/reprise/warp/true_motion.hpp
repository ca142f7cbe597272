// warp::motion_is_linear's survey over its samples alone, for callers whose frame is elsewhere
// (a GPU gathers the sampled pixels and reads back only those).
#pragma once

#include "reprise/core/camera.hpp"
#include "reprise/core/image.hpp"

namespace reprise::warp {

// The survey looks at pixels (4 + 8 i, 4 + 8 j): this many of `pixels` columns or rows.
inline constexpr int kLinearSurveyStep = 8;
constexpr int linear_survey_samples(int pixels) {
    return pixels > 0 ? (pixels + kLinearSurveyStep / 2 - 1) / kLinearSurveyStep : 0;
}

// motion_is_linear (reprise/warp/fruc.hpp) for a width x height frame seen by `camera` whose
// samples(i, j) holds (depth, motion x, motion y, -) of pixel (4 + 8 i, 4 + 8 j).
bool motion_is_linear(const Camera& camera, int width, int height,
                      ImageView<const glm::vec4> samples, const Camera& to, float factor,
                      float tolerance);

}  // namespace reprise::warp
