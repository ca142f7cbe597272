#include "fruc_options.hpp"

#include <cstdio>

namespace reprise::cli {

Status parse_fruc_options(const std::string& mode, const std::string& warp_name,
                          const std::string& fill, warp::FrucOptions& options) {
    using namespace warp;
    if (mode == "interpolate")
        options.mode = FrucMode::Interpolate;
    else if (mode == "extrapolate")
        options.mode = FrucMode::Extrapolate;
    else
        return Status::error("--mode '" + mode + "': expected interpolate or extrapolate");
    if (warp_name == "reverse")
        options.warp = WarpMethod::Reverse;
    else if (warp_name == "splat")
        options.warp = WarpMethod::Splat;
    else if (warp_name == "grid")
        options.warp = WarpMethod::Grid;
    else if (warp_name == "grid-bicubic" || warp_name == "grid-bilinear")
        options.warp = WarpMethod::Grid, options.grid.bicubic = warp_name == "grid-bicubic";
    else if (warp_name == "auto")
        options.warp = WarpMethod::Auto;
    else
        return Status::error("--warp '" + warp_name +
                             "': expected reverse, splat, grid, grid-bicubic, grid-bilinear or "
                             "auto");
    if (fill == "pullpush")
        options.fill = FillMethod::PullPush;
    else if (fill == "andreev")
        options.fill = FillMethod::Andreev;
    else if (fill == "none")
        options.fill = FillMethod::None;
    else if (fill == "auto")
        options.fill = FillMethod::Auto;
    else
        return Status::error("--fill '" + fill + "': expected pullpush, andreev, none or auto");
    return {};
}

Status parse_refine(const std::string& refine, warp::FrucOptions& options) {
    if (refine == "on")
        options.refine.enabled = true;
    else if (refine == "off")
        options.refine.enabled = false;
    else
        return Status::error("--refine '" + refine + "': expected on or off");
    return {};
}

std::string auto_choice_summary(const warp::FrucCounters& counters) {
    std::string text;
    char line[160];
    for (int k = 0; k < warp::kAutoCandidates; ++k) {
        if (counters.auto_chosen[k] == 0 && counters.auto_left_out[k] == 0) continue;
        std::snprintf(line, sizeof line, "    %-17s chosen %zu, left out %zu\n",
                      warp::auto_candidate_name(k), counters.auto_chosen[k],
                      counters.auto_left_out[k]);
        text += line;
    }
    return text;
}

}  // namespace reprise::cli
