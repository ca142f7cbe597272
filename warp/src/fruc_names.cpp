// Upconversion settings by name, shared by the command line and Python.
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
    else
        return Status::error("fill '" + fill + "': expected pullpush, andreev, none or auto");
    return {};
}

Status check_fruc_factor(int factor) {
    if (factor < 1 || factor > kMaxFrucFactor)
        return Status::error("factor " + std::to_string(factor) + ": expected 1.." +
                             std::to_string(kMaxFrucFactor));
    return {};
}

}  // namespace reprise::warp
