#include "fruc_options.hpp"

#include <cstdio>

namespace reprise::cli {

Status parse_fruc_options(const std::string& mode, const std::string& warp_name,
                          const std::string& fill, warp::FrucOptions& options) {
    const Status parsed = warp::fruc_options_from_names(mode, warp_name, fill, options);
    return parsed.ok() ? parsed : Status::error("--" + parsed.message());
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
