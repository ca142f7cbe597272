#include "depth_video_peer.hpp"

#include <algorithm>
#include <cmath>

#include "reprise/codec/codec.hpp"

namespace reprise::cli {

std::string depth_video_setting(const PeerConfig& config, int bits) {
    return peer_name(config.kind) + " " + std::to_string(bits) + "-bit " +
           (config.lossless ? config.preset + " lossless" : peer_setting(config));
}

Status code_depth_video(const std::vector<ImageView<const float>>& depths, double fps,
                        const PeerConfig& config, int bits, DepthVideo& out) {
    out = {};
    if (depths.empty()) return {};
    const int w = depths[0].width, h = depths[0].height;
    // The sequence's depth range, sent once as side information (two floats).
    float nearest = INFINITY, farthest = 0.0f;
    for (const ImageView<const float>& d : depths) {
        if (d.width != w || d.height != h)
            return Status::error("depth video peer: frames differ in size");
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                if (const float z = d(x, y); std::isfinite(z) && z > 0.0f)
                    nearest = std::min(nearest, z), farthest = std::max(farthest, z);
    }
    if (!(nearest <= farthest)) nearest = farthest = 1.0f;  // no geometry at all
    const double w_far = 1.0 / farthest, w_near = 1.0 / nearest;
    const double span = std::max(w_near - w_far, 1e-12);
    const int top = (1 << bits) - 1, floor = 1 << (bits - 4);  // codes below `floor`: background

    std::vector<std::vector<uint16_t>> planes(depths.size());
    for (std::size_t i = 0; i < depths.size(); ++i) {
        planes[i].resize(std::size_t(w) * h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const float z = depths[i](x, y);
                planes[i][std::size_t(y) * w + x] =
                    std::isfinite(z) && z > 0.0f
                        ? uint16_t(floor + std::lround((1.0 / z - w_far) / span * (top - floor)))
                        : uint16_t(0);
            }
    }
    std::vector<GreyFrame> coded;
    REPRISE_TRY(encode_decode_grey_peer(planes, w, h, bits, config, fps, coded));
    out.range_bytes = 8;
    out.decoded.resize(depths.size());
    for (std::size_t i = 0; i < depths.size(); ++i) {
        out.bytes.push_back(coded[i].bytes);
        out.encode_ms.push_back(coded[i].encode_ms);
        out.decode_ms.push_back(coded[i].decode_ms);
        Image<float>& back = out.decoded[i];
        back.resize(w, h);
        for (std::size_t p = 0; p < back.pixel_count(); ++p) {
            const int c = coded[i].decoded[p];
            back.data()[p] = c < floor / 2
                                 ? INFINITY
                                 : float(1.0 / (w_far + double(std::clamp(c, floor, top) - floor) /
                                                            (top - floor) * span));
        }
    }
    return {};
}

Status run_depth_video_peer(const std::vector<Frame>& frames, double fps, const PeerConfig& config,
                            int bits, float displacement, float bound_px, DepthVideoRun& run) {
    run = {};
    run.setting = depth_video_setting(config, bits);
    std::vector<ImageView<const float>> depths;
    for (const Frame& f : frames) depths.push_back(f.depth.view());
    DepthVideo video;
    REPRISE_TRY(code_depth_video(depths, fps, config, bits, video));
    run.bytes = double(video.range_bytes);
    std::size_t finite = 0, over = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        run.bytes += double(video.bytes[i]);
        run.encode_ms += video.encode_ms[i] / double(frames.size());
        run.decode_ms += video.decode_ms[i] / double(frames.size());
        const codec::ViewDepthError e =
            codec::measure_view_depth_error(frames[i].camera, frames[i].depth.view(),
                                            video.decoded[i].view(), displacement, bound_px);
        run.max_error_px = std::max(run.max_error_px, e.max_px);
        run.background_mismatches += e.background_mismatches;
        finite += e.pixels;
        over += e.pixels_over_bound;
    }
    run.share_over_bound = finite ? double(over) / double(finite) : 0.0;
    return {};
}

}  // namespace reprise::cli
