#include "depth_video_peer.hpp"

#include <algorithm>
#include <cmath>

#include "reprise/codec/codec.hpp"

namespace reprise::cli {

Status run_depth_video_peer(const std::vector<Frame>& frames, double fps, const PeerConfig& config,
                            int bits, float displacement, float bound_px, DepthVideoRun& run) {
    run = {};
    run.setting = peer_name(config.kind) + " " + std::to_string(bits) + "-bit " +
                  (config.lossless ? config.preset + " lossless" : peer_setting(config));
    if (frames.empty()) return {};
    const int w = frames[0].width(), h = frames[0].height();
    // The sequence's depth range, sent once as side information (two floats).
    float nearest = INFINITY, farthest = 0.0f;
    for (const Frame& f : frames)
        for (std::size_t p = 0; p < f.depth.pixel_count(); ++p) {
            const float z = f.depth.data()[p];
            if (std::isfinite(z) && z > 0.0f)
                nearest = std::min(nearest, z), farthest = std::max(farthest, z);
        }
    if (!(nearest <= farthest)) nearest = farthest = 1.0f;  // no geometry at all
    const double w_far = 1.0 / farthest, w_near = 1.0 / nearest;
    const double span = std::max(w_near - w_far, 1e-12);
    const int top = (1 << bits) - 1, floor = 1 << (bits - 4);  // codes below `floor`: background

    std::vector<std::vector<uint16_t>> planes(frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i) {
        if (frames[i].width() != w || frames[i].height() != h)
            return Status::error("depth video peer: frames differ in size");
        planes[i].resize(std::size_t(w) * h);
        for (std::size_t p = 0; p < planes[i].size(); ++p) {
            const float z = frames[i].depth.data()[p];
            planes[i][p] =
                std::isfinite(z) && z > 0.0f
                    ? uint16_t(floor + std::lround((1.0 / z - w_far) / span * (top - floor)))
                    : uint16_t(0);
        }
    }
    std::vector<GreyFrame> coded;
    REPRISE_TRY(encode_decode_grey_peer(planes, w, h, bits, config, fps, coded));
    run.bytes = 8.0;  // the depth range: two floats
    std::size_t finite = 0, over = 0;
    Image<float> back(w, h);
    for (std::size_t i = 0; i < frames.size(); ++i) {
        run.bytes += double(coded[i].bytes);
        run.encode_ms += coded[i].encode_ms / double(frames.size());
        run.decode_ms += coded[i].decode_ms / double(frames.size());
        for (std::size_t p = 0; p < back.pixel_count(); ++p) {
            const int c = coded[i].decoded[p];
            back.data()[p] = c < floor / 2
                                 ? INFINITY
                                 : float(1.0 / (w_far + double(std::clamp(c, floor, top) - floor) /
                                                            (top - floor) * span));
        }
        const codec::ViewDepthError e = codec::measure_view_depth_error(
            frames[i].camera, frames[i].depth.view(), back.view(), displacement, bound_px);
        run.max_error_px = std::max(run.max_error_px, e.max_px);
        run.background_mismatches += e.background_mismatches;
        finite += e.pixels;
        over += e.pixels_over_bound;
    }
    run.share_over_bound = finite ? double(over) / double(finite) : 0.0;
    return {};
}

}  // namespace reprise::cli
