#pragma once
// The names of upconversion settings on the command line and in reports.
#include <string>

#include "reprise/warp/fruc.hpp"

namespace reprise::cli {

// mode: interpolate|extrapolate; warp: reverse|splat|grid; fill: pullpush|andreev|none.
Status parse_fruc_options(const std::string& mode, const std::string& warp, const std::string& fill,
                          warp::FrucOptions& options);
// refine: on|off (motion refinement of interpolation by optical flow where the vectors are wrong).
Status parse_refine(const std::string& refine, warp::FrucOptions& options);

}  // namespace reprise::cli
