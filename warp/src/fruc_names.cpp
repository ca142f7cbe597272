// Upconversion settings by name, shared by the command line and Python.
#include <tuple>

#include "reprise/warp/fruc.hpp"

namespace reprise::warp {

Status fruc_options_from_names(const std::string& mode, const std::string& warp,
                               const std::string& fill, FrucOptions& options) {
    if (mode == "interpolate")
        options.mode = FrucMode::Interpolate;
    else if (mode == "extrapolate")
        options.mode = FrucMode::Extrapolate;
    else
        return Status::error("mode '" + mode + "': expected interpolate or extrapolate");
    if (warp == "reverse")
        options.warp = WarpMethod::Reverse;
    else if (warp == "splat")
        options.warp = WarpMethod::Splat;
    else if (warp == "grid")
        options.warp = WarpMethod::Grid;
    else if (warp == "grid-bicubic" || warp == "grid-bilinear")
        options.warp = WarpMethod::Grid, options.grid.bicubic = warp == "grid-bicubic";
    else if (warp == "auto")
        options.warp = WarpMethod::Auto;
    else
        return Status::error("warp '" + warp +
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
    else if (fill == "patch")
        options.fill = FillMethod::Patch;
    else
        return Status::error("fill '" + fill +
                             "': expected pullpush, andreev, patch, none or auto");
    return {};
}

namespace {

// "name value: expected lo..hi" unless lo <= value <= hi (NaN never is).
Status in_range(const char* name, double value, double lo, double hi) {
    if (value >= lo && value <= hi) return {};
    return Status::error(std::string("fruc option ") + name + " " + std::to_string(value) +
                         ": expected " + std::to_string(lo) + ".." + std::to_string(hi));
}

}  // namespace

Status check_fruc_options(const FrucOptions& o) {
    if (int(o.mode) < 0 || int(o.mode) > int(FrucMode::Extrapolate))
        return Status::error("fruc option mode " + std::to_string(int(o.mode)) + ": unknown");
    if (int(o.warp) < 0 || int(o.warp) > int(WarpMethod::Auto))
        return Status::error("fruc option warp " + std::to_string(int(o.warp)) + ": unknown");
    if (int(o.fill) < 0 || int(o.fill) > int(FillMethod::Patch))
        return Status::error("fruc option fill " + std::to_string(int(o.fill)) + ": unknown");
    if (o.warp == WarpMethod::Auto && o.fill == FillMethod::Patch)
        return Status::error(
            "fruc options warp auto and fill patch: the automatic choice has no model of the "
            "patch fill (give a fixed warp, or fill auto)");
    const double huge = 1e6;
    for (const auto& [name, value, lo, hi] : {
             std::tuple<const char*, double, double, double>{"cut_misses", o.cut_misses, 0, 1},
             {"cut_color", o.cut_color, 0, huge},
             {"static_tolerance", o.static_tolerance, 0, huge},
             {"grid.depth_threshold", o.grid.depth_threshold, 0, 0.5},
             {"grid.motion_threshold", o.grid.motion_threshold, 0, huge},
             {"splat.footprint", o.splat.footprint, 1, 2},
             {"splat.depth_tolerance", o.splat.depth_tolerance, 0, huge},
             {"refine.tile", o.refine.tile, 1, 1024},
             {"refine.threshold", o.refine.threshold, 0, huge},
             {"refine.tile_share", o.refine.tile_share, 0, 1},
             {"refine.margin", o.refine.margin, 0, 4096},
             {"refine.max_flow_share", o.refine.max_flow_share, 0, 1},
             {"auto_choice.budget_db", o.auto_choice.budget_db, 0, 1000},
             {"auto_choice.slack_db", o.auto_choice.slack_db, 0, 1000},
         })
        REPRISE_TRY(in_range(name, value, lo, hi));
    if (o.backend) REPRISE_TRY(o.backend->supports(o));
    return {};
}

Status check_fruc_factor(int factor) {
    if (factor < 1 || factor > kMaxFrucFactor)
        return Status::error("factor " + std::to_string(factor) + ": expected 1.." +
                             std::to_string(kMaxFrucFactor));
    return {};
}

}  // namespace reprise::warp
