#include "fruc_options.hpp"

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
    else
        return Status::error("--warp '" + warp_name +
                             "': expected reverse, splat, grid, grid-bicubic or grid-bilinear");
    if (fill == "pullpush")
        options.fill = FillMethod::PullPush;
    else if (fill == "andreev")
        options.fill = FillMethod::Andreev;
    else if (fill == "none")
        options.fill = FillMethod::None;
    else
        return Status::error("--fill '" + fill + "': expected pullpush, andreev or none");
    return {};
}

}  // namespace reprise::cli
