#pragma once
// Video codec peers of reprise's codec through libavcodec: x264, x265 and SVT-AV1 encode the
// same 8-bit sRGB display frames (yuv420p, limited range, BT.601 conversion by swscale), and
// libavcodec decodes them again (h264, hevc, libdav1d), timed per frame.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "reprise/core/status.hpp"
#include "reprise/core/visualize.hpp"

namespace reprise::cli {

enum class PeerKind { X264, X265, SvtAv1 };

struct PeerConfig {
    PeerKind kind = PeerKind::X264;
    std::string preset = "veryfast";  // x264/x265 preset name; SVT-AV1: a number 0..13
    int crf = 23;                     // the rate point: CRF (x264/x265 0..51, SVT-AV1 1..63)
    int threads = 2;                  // encoder and decoder threads
    int keyint = 0;                   // key frame interval; 0 = only the first frame
    bool lossless = false;            // x264 qp 0, x265 lossless=1 (crf unused)
};

// "x264", "x265", "svt-av1".
std::string peer_name(PeerKind kind);
// "veryfast crf 23" (names preset and rate point).
std::string peer_setting(const PeerConfig& config);
// Whether libavcodec has the encoder for `kind` (and a decoder for its format).
bool peer_available(PeerKind kind);

struct PeerFrame {
    std::size_t bytes = 0;   // the frame's packet
    double encode_ms = 0.0;  // RGB -> YUV conversion, send_frame and receive_packet
    double decode_ms = 0.0;  // send_packet, receive_frame and YUV -> RGB conversion
    double encode_convert_ms = 0.0, decode_convert_ms = 0.0;  // the conversions alone
    Image<Rgb8> decoded;                                      // same size as the input
};

// Encodes `frames` (all the same size, at least 2x2) as one low-delay stream (tune
// zerolatency for x264/x265, no B-frames; SVT-AV1 low-delay prediction structure) and decodes
// it; `out` gets one entry per input frame. Sizes the encoder cannot take (odd sides, SVT-AV1
// below 64 or not a multiple of 8) are padded by repeating the last row/column and the decoded
// frames cropped back. Errors name the codec and the libavcodec call.
Status encode_decode_peer(const std::vector<Image<Rgb8>>& frames, const PeerConfig& config,
                          double fps, std::vector<PeerFrame>& out);

// Grey video, as immersive-video systems send depth: each plane's w x h samples (0..2^bits - 1,
// row-major) as gray10le / gray12le luma through x264 (High 10, 4:0:0) or x265 (4:0:0, 12 bits
// too), decoded again; `out` gets the decoded planes, bytes and times.
struct GreyFrame {
    std::size_t bytes = 0;
    double encode_ms = 0.0, decode_ms = 0.0, encode_convert_ms = 0.0, decode_convert_ms = 0.0;
    std::vector<uint16_t> decoded;
};
Status encode_decode_grey_peer(const std::vector<std::vector<uint16_t>>& planes, int w, int h,
                               int bits, const PeerConfig& config, double fps,
                               std::vector<GreyFrame>& out);

// The streaming configurations of issue 8 §6, each at four rate points: x264 ultrafast,
// veryfast, medium; x265 ultrafast; SVT-AV1 preset 10 (all low delay, zerolatency).
std::vector<PeerConfig> standard_peer_configs(int threads);

}  // namespace reprise::cli
