#pragma once
// The names of upconversion settings on the command line and in reports.
#include <string>

#include "reprise/warp/fruc.hpp"

namespace reprise::cli {

// mode: interpolate|extrapolate; warp: reverse|splat|grid|auto; fill: pullpush|andreev|none|auto.
Status parse_fruc_options(const std::string& mode, const std::string& warp, const std::string& fill,
                          warp::FrucOptions& options);
// refine: on|off (motion refinement of interpolation by optical flow where the vectors are wrong).
Status parse_refine(const std::string& refine, warp::FrucOptions& options);

// What an auto choice chose and left out, one line per candidate that was either: "  grid+pullpush
// chosen 12, left out 0".
std::string auto_choice_summary(const warp::FrucCounters& counters);

}  // namespace reprise::cli
