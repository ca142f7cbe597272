#pragma once
// The depth peer of immersive-video systems (MPEG Immersive Video, 3D-HEVC practice): 1/z
// between the sequence's nearest and farthest depth mapped linearly onto 10- or 12-bit grey,
// background as codes below an occupancy threshold, sent as a video of its own through x265 or
// x264 High 10; the client maps the decoded grey back to depth.
#include <string>
#include <vector>

#include "codec_peers.hpp"
#include "reprise/core/frame.hpp"

namespace reprise::cli {

struct DepthVideoRun {
    std::string setting;                      // "x265 10-bit crf 20"
    double bytes = 0.0;                       // the whole sequence's depth video
    double encode_ms = 0.0, decode_ms = 0.0;  // per frame, mean
    double max_error_px = 0.0;      // reprojection error of decoded against rendered depth
    double share_over_bound = 0.0;  // of finite pixels, moved by more than the bound
    std::size_t background_mismatches = 0;
};

// "x265 10-bit veryfast crf 8", "x265 10-bit veryfast lossless".
std::string depth_video_setting(const PeerConfig& config, int bits);

// The depth video itself: `decoded` depth (background +inf) and bytes per frame, plus the depth
// range sent once.
struct DepthVideo {
    std::vector<Image<float>> decoded;
    std::vector<std::size_t> bytes;
    std::vector<double> encode_ms, decode_ms;
    std::size_t range_bytes = 0;
};
Status code_depth_video(const std::vector<ImageView<const float>>& depths, double fps,
                        const PeerConfig& config, int bits, DepthVideo& out);

// Codes the depth of `frames` (with cameras) as grey video and measures, per frame, the
// reprojection error its decoded depth causes for a camera displaced by up to `displacement`
// (codec::measure_view_depth_error), counting pixels beyond `bound_px`.
Status run_depth_video_peer(const std::vector<Frame>& frames, double fps, const PeerConfig& config,
                            int bits, float displacement, float bound_px, DepthVideoRun& run);

}  // namespace reprise::cli
