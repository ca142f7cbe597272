#include "codec_peers.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/error.h>
#include <libavutil/frame.h>
#include <libavutil/opt.h>
#include <libavutil/pixdesc.h>
#include <libswscale/swscale.h>
}

#include "bench_report.hpp"

namespace reprise::cli {

namespace {

const char* encoder_name(PeerKind kind) {
    switch (kind) {
        case PeerKind::X264:
            return "libx264";
        case PeerKind::X265:
            return "libx265";
        case PeerKind::SvtAv1:
            return "libsvtav1";
    }
    return "";
}

const char* decoder_name(PeerKind kind) {
    switch (kind) {
        case PeerKind::X264:
            return "h264";
        case PeerKind::X265:
            return "hevc";
        case PeerKind::SvtAv1:
            return "libdav1d";
    }
    return "";
}

std::string av_message(int code) {
    char text[AV_ERROR_MAX_STRING_SIZE] = {};
    av_strerror(code, text, sizeof text);
    return text;
}

// Owners of the libavcodec objects, released on every path.
struct CodecContext {
    AVCodecContext* context = nullptr;
    ~CodecContext() { avcodec_free_context(&context); }
};
struct FrameOwner {
    AVFrame* frame = av_frame_alloc();
    ~FrameOwner() { av_frame_free(&frame); }
};
struct PacketOwner {
    AVPacket* packet = av_packet_alloc();
    ~PacketOwner() { av_packet_free(&packet); }
};
struct ScaleOwner {
    SwsContext* context = nullptr;
    ~ScaleOwner() { sws_freeContext(context); }
};

int padded_side(PeerKind kind, int side) {
    if (kind == PeerKind::SvtAv1) return std::max(64, (side + 7) / 8 * 8);
    return (side + 1) / 2 * 2;
}

Status open_encoder(const PeerConfig& config, int w, int h, double fps, AVPixelFormat format,
                    CodecContext& out) {
    const std::string who = peer_name(config.kind) + ": ";
    const AVCodec* codec = avcodec_find_encoder_by_name(encoder_name(config.kind));
    if (!codec)
        return Status::error(who + "libavcodec has no encoder " + encoder_name(config.kind));
    AVCodecContext* c = out.context = avcodec_alloc_context3(codec);
    if (!c) return Status::error(who + "avcodec_alloc_context3 failed");
    const int rate = std::max(1, int(std::lround(fps)));
    c->width = w;
    c->height = h;
    c->time_base = {1, rate};
    c->framerate = {rate, 1};
    c->pix_fmt = format;
    c->gop_size = config.keyint > 0 ? config.keyint : 100000;
    c->max_b_frames = 0;
    c->thread_count = config.threads;
    const std::string crf = std::to_string(config.crf);
    int err = 0;
    auto set = [&](const char* key, const std::string& value) {
        if (err >= 0) err = av_opt_set(c->priv_data, key, value.c_str(), 0);
        return err;
    };
    switch (config.kind) {
        case PeerKind::X264:
            set("preset", config.preset), set("tune", "zerolatency");
            set(config.lossless ? "qp" : "crf", config.lossless ? "0" : crf);
            break;
        case PeerKind::X265:
            set("preset", config.preset), set("tune", "zerolatency"), set("crf", crf);
            set("x265-params",
                std::string("bframes=0:log-level=error") + (config.lossless ? ":lossless=1" : ""));
            break;
        case PeerKind::SvtAv1:
            set("preset", config.preset), set("crf", crf);
            set("svtav1-params", "pred-struct=1:lp=" + std::to_string(config.threads));
            break;
    }
    if (err < 0) return Status::error(who + "av_opt_set: " + av_message(err));
    err = avcodec_open2(c, codec, nullptr);
    if (err < 0) return Status::error(who + "avcodec_open2 (encoder): " + av_message(err));
    return {};
}

Status open_decoder(const PeerConfig& config, CodecContext& out) {
    const std::string who = peer_name(config.kind) + ": ";
    const AVCodec* codec = avcodec_find_decoder_by_name(decoder_name(config.kind));
    if (!codec)
        return Status::error(who + "libavcodec has no decoder " + decoder_name(config.kind));
    AVCodecContext* c = out.context = avcodec_alloc_context3(codec);
    if (!c) return Status::error(who + "avcodec_alloc_context3 failed");
    c->thread_count = config.threads;
    c->thread_type = FF_THREAD_SLICE;  // frame threads would hold frames back
    c->flags |= AV_CODEC_FLAG_LOW_DELAY;
    const int err = avcodec_open2(c, codec, nullptr);
    if (err < 0) return Status::error(who + "avcodec_open2 (decoder): " + av_message(err));
    return {};
}

// Packed RGB rows for swscale: 64-byte aligned strides and slack at the end, because its SIMD
// paths read and write past the last pixel of a row whose width is not a multiple of 16.
struct RgbBuffer {
    int width = 0, height = 0, stride = 0;  // stride in bytes
    std::vector<uint8_t> bytes;
    RgbBuffer(int w, int h) : width(w), height(h), stride((w * 3 + 63) / 64 * 64) {
        bytes.assign(std::size_t(stride) * (h + 1) + 64, 0);
    }
    uint8_t* row(int y) { return bytes.data() + std::size_t(stride) * y; }
};

// `frame` (w x h) into `padded` (larger or equal), repeating the last column and row.
void pad(const Image<Rgb8>& frame, RgbBuffer& padded) {
    const int w = frame.width(), h = frame.height();
    for (int y = 0; y < padded.height; ++y) {
        uint8_t* row = padded.row(y);
        for (int x = 0; x < padded.width; ++x) {
            const Rgb8 c = frame(std::min(x, w - 1), std::min(y, h - 1));
            row[3 * x] = c.r, row[3 * x + 1] = c.g, row[3 * x + 2] = c.b;
        }
    }
}

}  // namespace

std::string peer_name(PeerKind kind) {
    switch (kind) {
        case PeerKind::X264:
            return "x264";
        case PeerKind::X265:
            return "x265";
        case PeerKind::SvtAv1:
            return "svt-av1";
    }
    return "?";
}

std::string peer_setting(const PeerConfig& config) {
    return (config.kind == PeerKind::SvtAv1 ? "p" : "") + config.preset + " crf " +
           std::to_string(config.crf);
}

bool peer_available(PeerKind kind) {
    return avcodec_find_encoder_by_name(encoder_name(kind)) &&
           avcodec_find_decoder_by_name(decoder_name(kind));
}

std::vector<PeerConfig> standard_peer_configs(int threads) {
    std::vector<PeerConfig> configs;
    for (const char* preset : {"ultrafast", "veryfast", "medium"})
        for (int crf : {20, 26, 32, 38})
            configs.push_back(
                {.kind = PeerKind::X264, .preset = preset, .crf = crf, .threads = threads});
    for (int crf : {20, 26, 32, 38})
        configs.push_back(
            {.kind = PeerKind::X265, .preset = "ultrafast", .crf = crf, .threads = threads});
    for (int crf : {28, 38, 48, 58})
        configs.push_back(
            {.kind = PeerKind::SvtAv1, .preset = "10", .crf = crf, .threads = threads});
    return configs;
}

namespace {

// One low-delay stream through libavcodec: `fill(i, frame)` writes input i into a writable
// frame of `format` (pw x ph), `take(i, frame)` reads decoded frame i; both return the ms they
// spent converting. `out[i]` gets the bytes and times of frame i (out.size() frames).
template <class PeerOutput, class Fill, class Take>
Status run_peer_codec(const PeerConfig& config, int pw, int ph, double fps, AVPixelFormat format,
                      Fill fill, Take take, std::vector<PeerOutput>& out) {
    const std::string who = peer_name(config.kind) + ": ";
    if (config.threads < 1 || config.threads > 64)
        return Status::error(who + "threads must be in 1..64");
    if (config.kind == PeerKind::SvtAv1 && !std::getenv("SVT_LOG"))
        setenv("SVT_LOG", "1", 0);  // errors only: SVT-AV1 prints its configuration otherwise
    av_log_set_level(AV_LOG_ERROR);
    CodecContext encoder, decoder;
    REPRISE_TRY(open_encoder(config, pw, ph, fps, format, encoder));
    REPRISE_TRY(open_decoder(config, decoder));
    FrameOwner input, decoded;
    PacketOwner packet;
    if (!input.frame || !decoded.frame || !packet.packet)
        return Status::error(who + "out of memory");
    input.frame->format = format;
    input.frame->width = pw;
    input.frame->height = ph;
    int err = av_frame_get_buffer(input.frame, 0);
    if (err < 0) return Status::error(who + "av_frame_get_buffer: " + av_message(err));

    // Encode: packets in output order, with the frame index they carry.
    std::vector<std::vector<uint8_t>> packets;
    std::vector<int> packet_frame;
    auto drain = [&](double& ms_of_call) -> Status {
        for (;;) {
            const auto start = BenchClock::now();
            err = avcodec_receive_packet(encoder.context, packet.packet);
            ms_of_call += ms_since(start);
            if (err == AVERROR(EAGAIN) || err == AVERROR_EOF) return {};
            if (err < 0) return Status::error(who + "avcodec_receive_packet: " + av_message(err));
            packets.emplace_back(packet.packet->data, packet.packet->data + packet.packet->size);
            packet_frame.push_back(int(packet.packet->pts));
            av_packet_unref(packet.packet);
        }
    };
    for (std::size_t i = 0; i < out.size(); ++i) {
        const auto start = BenchClock::now();
        err = av_frame_make_writable(input.frame);
        if (err < 0) return Status::error(who + "av_frame_make_writable: " + av_message(err));
        double ms = ms_since(start);
        out[i].encode_convert_ms = fill(i, input.frame);
        ms += out[i].encode_convert_ms;
        input.frame->pts = int64_t(i);
        const auto send = BenchClock::now();
        err = avcodec_send_frame(encoder.context, input.frame);
        ms += ms_since(send);
        if (err < 0) return Status::error(who + "avcodec_send_frame: " + av_message(err));
        REPRISE_TRY(drain(ms));
        out[i].encode_ms = ms;
    }
    {
        double ms = 0.0;
        const std::size_t before = packets.size();
        const auto start = BenchClock::now();
        err = avcodec_send_frame(encoder.context, nullptr);
        ms += ms_since(start);
        if (err < 0) return Status::error(who + "avcodec_send_frame (flush): " + av_message(err));
        REPRISE_TRY(drain(ms));
        // Frames that came out only at the flush share its time.
        for (std::size_t k = before; k < packets.size(); ++k)
            if (packet_frame[k] >= 0 && std::size_t(packet_frame[k]) < out.size())
                out[packet_frame[k]].encode_ms += ms / double(packets.size() - before);
    }
    for (std::size_t k = 0; k < packets.size(); ++k) {
        if (packet_frame[k] < 0 || std::size_t(packet_frame[k]) >= out.size())
            return Status::error(who + "a packet carries an unknown frame number");
        out[packet_frame[k]].bytes += packets[k].size();
    }

    // Decode, in packet order; decoded frames come out in presentation order (no B-frames).
    std::size_t next = 0;
    auto receive = [&](double& ms_of_call) -> Status {
        for (;;) {
            const auto start = BenchClock::now();
            err = avcodec_receive_frame(decoder.context, decoded.frame);
            ms_of_call += ms_since(start);
            if (err == AVERROR(EAGAIN) || err == AVERROR_EOF) return {};
            if (err < 0) return Status::error(who + "avcodec_receive_frame: " + av_message(err));
            if (next >= out.size()) return Status::error(who + "the decoder made extra frames");
            AVFrame* f = decoded.frame;
            if (f->width != pw || f->height != ph)
                return Status::error(who + "decoded frame has another size");
            // `take` times its conversion; copying into the output is not the decoder's work.
            PeerOutput& target = out[next];
            target.decode_convert_ms = take(next++, f);
            ms_of_call += target.decode_convert_ms;
            av_frame_unref(f);
            target.decode_ms += ms_of_call;
            ms_of_call = 0.0;
        }
    };
    double pending_ms = 0.0;  // decoder time not yet given to a frame
    for (const std::vector<uint8_t>& bytes : packets) {
        av_packet_unref(packet.packet);
        err = av_new_packet(packet.packet, int(bytes.size()));
        if (err < 0) return Status::error(who + "av_new_packet: " + av_message(err));
        std::copy(bytes.begin(), bytes.end(), packet.packet->data);
        const auto start = BenchClock::now();
        err = avcodec_send_packet(decoder.context, packet.packet);
        pending_ms += ms_since(start);
        if (err < 0) return Status::error(who + "avcodec_send_packet: " + av_message(err));
        REPRISE_TRY(receive(pending_ms));
    }
    const auto start = BenchClock::now();
    err = avcodec_send_packet(decoder.context, nullptr);
    pending_ms += ms_since(start);
    if (err < 0) return Status::error(who + "avcodec_send_packet (flush): " + av_message(err));
    REPRISE_TRY(receive(pending_ms));
    if (next != out.size())
        return Status::error(who + "decoded " + std::to_string(next) + " of " +
                             std::to_string(out.size()) + " frames");
    return {};
}

Status check_size(const std::string& who, int w, int h) {
    if (w < 2 || h < 2 || w > 8192 || h > 8192)
        return Status::error(who + "frame size " + std::to_string(w) + "x" + std::to_string(h) +
                             " outside 2x2..8192x8192");
    return {};
}

}  // namespace

Status encode_decode_peer(const std::vector<Image<Rgb8>>& frames, const PeerConfig& config,
                          double fps, std::vector<PeerFrame>& out) {
    const std::string who = peer_name(config.kind) + ": ";
    out.clear();
    if (frames.empty()) return {};
    const int w = frames[0].width(), h = frames[0].height();
    REPRISE_TRY(check_size(who, w, h));
    for (const Image<Rgb8>& f : frames)
        if (f.width() != w || f.height() != h) return Status::error(who + "frames differ in size");
    const int pw = padded_side(config.kind, w), ph = padded_side(config.kind, h);
    ScaleOwner to_yuv, to_rgb;
    to_yuv.context = sws_getContext(pw, ph, AV_PIX_FMT_RGB24, pw, ph, AV_PIX_FMT_YUV420P,
                                    SWS_BICUBIC, nullptr, nullptr, nullptr);
    if (!to_yuv.context) return Status::error(who + "sws_getContext (RGB -> YUV) failed");
    RgbBuffer padded(pw, ph), shown(pw, ph);
    bool converted = true;
    auto fill = [&](std::size_t i, AVFrame* yuv) {
        pad(frames[i], padded);
        const auto start = BenchClock::now();
        const uint8_t* src[1] = {padded.row(0)};
        const int src_stride[1] = {padded.stride};
        sws_scale(to_yuv.context, src, src_stride, 0, ph, yuv->data, yuv->linesize);
        return ms_since(start);
    };
    auto take = [&](std::size_t i, const AVFrame* f) {
        to_rgb.context =
            sws_getCachedContext(to_rgb.context, pw, ph, AVPixelFormat(f->format), pw, ph,
                                 AV_PIX_FMT_RGB24, SWS_BICUBIC, nullptr, nullptr, nullptr);
        if (!to_rgb.context) return converted = false, 0.0;
        uint8_t* dst[1] = {shown.row(0)};
        const int dst_stride[1] = {shown.stride};
        const auto start = BenchClock::now();
        sws_scale(to_rgb.context, f->data, f->linesize, 0, ph, dst, dst_stride);
        const double ms = ms_since(start);
        Image<Rgb8>& target = out[i].decoded;
        target.resize(w, h);
        for (int y = 0; y < h; ++y) {
            const uint8_t* row = shown.row(y);
            for (int x = 0; x < w; ++x)
                target(x, y) = Rgb8(row[3 * x], row[3 * x + 1], row[3 * x + 2]);
        }
        return ms;
    };
    out.resize(frames.size());
    REPRISE_TRY(run_peer_codec(config, pw, ph, fps, AV_PIX_FMT_YUV420P, fill, take, out));
    if (!converted) return Status::error(who + "sws_getContext (YUV -> RGB) failed");
    return {};
}

Status encode_decode_grey_peer(const std::vector<std::vector<uint16_t>>& planes, int w, int h,
                               int bits, const PeerConfig& config, double fps,
                               std::vector<GreyFrame>& out) {
    const std::string who = peer_name(config.kind) + " (grey): ";
    out.clear();
    if (planes.empty()) return {};
    REPRISE_TRY(check_size(who, w, h));
    if (config.kind == PeerKind::SvtAv1 || (bits != 10 && bits != 12) ||
        (bits == 12 && config.kind != PeerKind::X265))
        return Status::error(who + "grey video is 10-bit x264 or x265, or 12-bit x265");
    for (const std::vector<uint16_t>& p : planes)
        if (p.size() != std::size_t(w) * h)
            return Status::error(who + "a plane is not " + std::to_string(w) + "x" +
                                 std::to_string(h));
    const int pw = padded_side(config.kind, w), ph = padded_side(config.kind, h);
    auto fill = [&](std::size_t i, AVFrame* grey) {
        const auto start = BenchClock::now();
        for (int y = 0; y < ph; ++y) {
            auto* row =
                reinterpret_cast<uint16_t*>(grey->data[0] + std::ptrdiff_t(y) * grey->linesize[0]);
            const uint16_t* from = planes[i].data() + std::size_t(std::min(y, h - 1)) * w;
            for (int x = 0; x < pw; ++x) row[x] = from[std::min(x, w - 1)];
        }
        return ms_since(start);
    };
    bool grey_out = true;
    auto take = [&](std::size_t i, const AVFrame* f) {
        const auto start = BenchClock::now();
        // libavcodec's H.264 decoder gives 4:0:0 as 4:2:0 with grey chroma: the luma plane counts.
        const AVPixFmtDescriptor* d = av_pix_fmt_desc_get(AVPixelFormat(f->format));
        grey_out = grey_out && d && !(d->flags & (AV_PIX_FMT_FLAG_RGB | AV_PIX_FMT_FLAG_BE)) &&
                   d->comp[0].plane == 0 && d->comp[0].step == 2 && d->comp[0].depth == bits;
        std::vector<uint16_t>& target = out[i].decoded;
        target.assign(std::size_t(w) * h, 0);
        if (grey_out)
            for (int y = 0; y < h; ++y) {
                const auto* row = reinterpret_cast<const uint16_t*>(
                    f->data[0] + std::ptrdiff_t(y) * f->linesize[0]);
                std::copy(row, row + w, target.begin() + std::ptrdiff_t(y) * w);
            }
        return ms_since(start);
    };
    out.resize(planes.size());
    REPRISE_TRY(run_peer_codec(config, pw, ph, fps,
                               bits == 10 ? AV_PIX_FMT_GRAY10LE : AV_PIX_FMT_GRAY12LE, fill, take,
                               out));
    if (!grey_out)
        return Status::error(who + "the decoder gave a format without " + std::to_string(bits) +
                             "-bit luma");
    return {};
}

}  // namespace reprise::cli
