#pragma once
// Scene-aware predictive codec: each frame is predicted by reprojecting a reference the decoder
// holds with the renderer's depth, cameras and motion; only what prediction gets wrong is coded.
// Bitstream: docs/bitstream.md. Encoder and decoder are push/pull stages (reprise/core/status.hpp).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/ext/vector_uint4_sized.hpp>

#include "reprise/core/frame.hpp"
#include "reprise/core/nonfinite.hpp"

namespace reprise::codec {

enum class Chroma : uint8_t { C420 = 0, C444 = 1 };
enum class DepthMode : uint8_t {
    Lossless = 0,  // bit-exact float depth
    Bounded = 1,   // relative error of z (and of 1/z) at most depth_error
    None = 2,      // no depth: the renderer's motion is sent whole (1/8 px), predicting colour
    // 1/z quantised uniformly, the step chosen so that moving the camera by up to
    // view_displacement moves no reprojected pixel by more than view_error_px (docs/bitstream.md)
    View = 3,
};

struct EncoderOptions {
    int qp = 28;           // quantiser, 0 (finest) .. 51; constant quality when bitrate_kbps = 0
    int bitrate_kbps = 0;  // > 0: rate control to this bitrate (frames bounded in size)
    double fps = 30.0;     // for rate control and timestamps when the frames carry none
    int keyint = 0;        // a key frame at least every keyint frames; 0 = only on cuts/requests
    Chroma chroma = Chroma::C420;
    DepthMode depth = DepthMode::Lossless;
    float depth_error = 1e-4f;  // relative bound for DepthMode::Bounded
    // DepthMode::View: the largest reprojection error (pixels) a camera displacement of up to
    // view_displacement (scene units; default 10 cm of extrapolation plus a 64 mm eye distance)
    // may cause.
    float view_error_px = 0.25f;
    float view_displacement = 0.164f;
    // Largest distance (px) between decoded and rendered motion: affine models per block where
    // they hold (docs/bitstream.md). 0 = every pixel to 1/8 px. Otherwise 0.1 .. 8.
    float motion_error_px = 0.25f;
    // Above qp 34 both bounds double every 6 qp, as the colour quantiser's step does: depth and
    // motion finer than the colour they move cost bits the decoded picture does not show
    // (docs/bitstream.md). false: the bounds as given at every qp. Under rate control they
    // follow `qp` (the starting quantiser), fixed for the stream.
    bool bounds_follow_qp = true;
    // A block whose prediction error stays within this many 8-bit display levels on every
    // channel is skipped (Mueller et al. 2021: T = 8/255 stays under one JND). 0 = skip only
    // what quantises to nothing.
    int skip_threshold = 2;
    // A frame whose camera says Cut::Yes is a key frame. One whose camera does not say
    // (Cut::Unknown) is a key frame when the prediction misses most pixels, if detect_cuts.
    bool detect_cuts = true;
    // Frames without a camera (identity matrices) and with depth and motion are coded with a
    // camera fitted to them, so that only motion it does not explain is sent (docs/bitstream.md).
    bool fit_cameras = true;
    // With motion models (motion_error_px > 0) and depth: each object id that moves on its own
    // gets a rigid motion fitted to its pixels, from which both sides derive its pixels' motion
    // and predict its depth (docs/bitstream.md).
    bool rigid_objects = true;
    // Slices coded in parallel, each with its own models (fewer cost fewer bits): 0 = one per 24
    // macroblock rows (720p: 2, 1080p: 3); at most 64 and one per macroblock row.
    int slices = 0;
};

enum class PacketType : uint8_t { Key = 0, Inter = 1 };

struct Packet {
    std::vector<uint8_t> data;  // header + payload, as sent
    uint32_t frame = 0;
    uint32_t reference = 0;  // frame it was predicted from (== frame for key frames)
    PacketType type = PacketType::Key;
};

// Bits per stream and what was left out, accumulated over the frames encoded or decoded.
struct StreamStats {
    std::size_t frames = 0;
    std::size_t key_frames = 0;
    std::size_t older_reference = 0;  // predicted from a frame before the previous one
    std::size_t header_bits = 0, camera_bits = 0, depth_bits = 0, motion_bits = 0, color_bits = 0;
    std::size_t blocks = 0;                  // 8x8 colour transform blocks (all planes)
    std::size_t blocks_skipped = 0;          // coded as a flag only
    std::size_t intra_blocks = 0;            // macroblocks predicted from the current frame
    std::size_t motion_residual_pixels = 0;  // pixels whose motion the cameras do not explain
    std::size_t motion_models = 0;           // affine motion models sent
    std::size_t motion_own_pixels = 0;       // pixels whose motion no model gives, sent alone
    std::size_t motion_objects = 0;          // rigid object motions sent
    std::size_t depth_zero_blocks = 0;       // depth blocks predicted exactly
    std::size_t depth_plane_blocks = 0;      // depth blocks predicted by a plane they send
    // Encoder: where the depth section's bits go (the coder's ideal lengths, bits): each block's
    // flags (temporal, plane, no residual), plane parameters, then the pixels of blocks with
    // residuals: of key frames, and in inter frames of moving objects held to their finer step,
    // of pixels nothing of the reference landed on (revealed), of the rest (the reference saw).
    struct DepthBits {
        double flags = 0.0, planes = 0.0, key = 0.0, objects = 0.0, revealed = 0.0, seen = 0.0;
        double total() const { return flags + planes + key + objects + revealed + seen; }
        DepthBits& operator+=(const DepthBits& o) {
            flags += o.flags, planes += o.planes, key += o.key, objects += o.objects;
            revealed += o.revealed, seen += o.seen;
            return *this;
        }
    } depth_parts;
    // Encoder: where the motion bits go (bits; ideal lengths but for `objects`): the quadtree's
    // flags (zero, merge, object, split; a 4x4 cell's pixel-by-pixel and object flags), new affine
    // models' parameters, the cells coded pixel by pixel (per-pixel motion, M = 0: its block flags
    // as tree, its pixels as pixels), and the rigid objects' list (in the camera section).
    struct MotionBits {
        double tree = 0.0, models = 0.0, pixels = 0.0, objects = 0.0;
        double total() const { return tree + models + pixels + objects; }
        MotionBits& operator+=(const MotionBits& o) {
            tree += o.tree, models += o.models, pixels += o.pixels, objects += o.objects;
            return *this;
        }
    } motion_parts;
    std::size_t revealed_pixels =
        0;                           // colour predicted from beside: the reference did not see them
    std::size_t cameras_fitted = 0;  // encoder: frames without a camera coded with a fitted one
    // Encoder input: NaN/Inf repaired before coding (colour: holes; depth NaN/-inf and motion:
    // unknown; reprise/core/nonfinite.hpp).
    NonfiniteCounts nonfinite;
    // Wall-clock milliseconds by stage, on the coder's threads: where the time goes.
    struct Milliseconds {
        double input = 0.0;      // encoder: NaN/Inf repair and the camera fit
        double convert = 0.0;    // colour between linear RGB and the coded planes
        double objects = 0.0;    // encoder: rigid object motions fitted
        double reproject = 0.0;  // the reference's depth reprojected (depth's prediction)
        double depth = 0.0;      // depth predicted and coded, without the reprojection
        double motion = 0.0;     // motion coded, then turned into motion to the reference
        double predict = 0.0;    // colour predicted from the reference (revealed pixels filled)
        double color = 0.0;      // colour transformed, coded and deblocked, without prediction
        double total() const {
            return input + convert + objects + reproject + depth + motion + predict + color;
        }
    } ms;
    std::size_t total_bits() const {
        return header_bits + camera_bits + depth_bits + motion_bits + color_bits;
    }
};

// The view and motion bounds (px) a stream of these options is coded to (bounds_follow_qp).
struct CodedBounds {
    float view_error_px = 0.0f, motion_error_px = 0.0f;
};
CodedBounds coded_bounds(const EncoderOptions& options);

// Adds one frame's (or stream's) counts to a running total.
void add_stats(StreamStats& total, const StreamStats& frame);

// The options' values in their ranges: an error naming the first that is not.
Status check_encoder_options(const EncoderOptions& options);

class Encoder {
public:
    Encoder();  // default options
    // Checks the options (check_encoder_options), then makes `encoder` a new encoder with them;
    // on an error it is left as it was.
    static Status create(const EncoderOptions& options, Encoder& encoder);
    ~Encoder();
    Encoder(Encoder&&) noexcept;
    Encoder& operator=(Encoder&&) noexcept;

    // Encodes one frame, read through the G-buffer descriptor and not kept (colour required and
    // setting the size; depth, motion, id and the camera enable prediction, fps rate control).
    // A Frame converts to it. The packet then comes out of receive_packet(). An error for a frame
    // it cannot code (sizes, memory, more than 16 packets not taken); the encoder stays usable.
    Status send_frame(const GBufferView& frame);
    // The same with the colour as 8-bit sRGB display values (RGBA8, alpha not read; an engine's
    // swapchain image, say), coded as they are: frame.color is not read (it may be empty), and
    // the display values set the size.
    Status send_frame(const GBufferView& frame, ImageView<const glm::u8vec4> display);
    // Ok with the next packet in `packet`, or NeedMoreData: send the next frame first.
    Result receive_packet(Packet& packet);
    void flush();  // no delayed frames: kept for the state-machine shape

    // Feedback from the receiver: frame n was decoded / was lost.
    void acknowledge(uint32_t frame);
    void report_loss(uint32_t frame);
    void request_key_frame();
    // Continues the stream whose packets so far are `packets` (an interrupted encode): decodes
    // them into the references and rate-control state this encoder would hold after them, so
    // that the next send_frame writes what one encoder over the whole sequence would have.
    // Only on an encoder that has encoded nothing; every packet must decode, frames 0, 1, ...
    // `fps`: the rate each of those frames was sent with (GBufferView::fps; 0: the options'),
    // which rate control divides the bitrate by and the stream does not hold; empty: every
    // frame at the stream's (its key frame's), exact for a constant rate only.
    Status resume(std::span<const std::span<const uint8_t>> packets,
                  std::span<const double> fps = {});
    // Changes the rate-control target from the next frame on (0 = constant quality at qp); no
    // key frame is forced.
    void set_bitrate(int kbps);
    int bitrate() const;

    // What the decoder holds after the last packet: colour in linear light, decoded depth and
    // motion, camera (bit-identical to the decoder's output).
    const Frame& reconstruction() const;
    const StreamStats& stats() const;
    // Bits of the last packet per stream.
    const StreamStats& last_frame_stats() const;
    int last_qp() const;

    struct State;

private:
    std::unique_ptr<State> state_;
};

struct DecoderOptions {
    // Key frames announcing more pixels are refused: what one stream can make the decoder
    // allocate is bounded (about 60 bytes per pixel for the references it keeps).
    int64_t max_pixels = int64_t(8192) * 4320;
    // Off: decoded frames carry no colour (Frame::color empty; the size is depth's), for a
    // geometry stream whose colour the caller does not use (lowres streaming). The colour planes
    // are still decoded: the next frames predict from them.
    bool color = true;
    // On (with `color`): the colour comes as the 8-bit sRGB display values the stream codes
    // (DecodedFrame::display, RGBA8, A 255 where depth is finite or absent, else 0) instead of
    // linear light, for a client that shows them: a quarter of the bytes and no conversion.
    bool display = false;
};

// A decoded frame that shares the decoder's picture, as dav1d hands out its pictures: depth and
// motion are read where the decoder keeps them to predict the next frames, with no copy, and
// stay valid (unchanged) while this object holds the picture; colour is its own. Non-finite depth
// or motion (a lossless stream can spell NaN) comes repaired, in a copy of the channel.
class DecodedFrame {
public:
    Image<glm::vec4> color;  // linear light; empty with DecoderOptions::color = false or display
    Image<glm::u8vec4> display;  // with DecoderOptions::display: 8-bit sRGB display values
    Camera camera;
    double fps = 0.0;

    ImageView<const float> depth() const { return depth_; }
    ImageView<const glm::vec2> motion() const { return motion_; }
    int width() const { return depth_.width; }  // depth sets the size (colour may be absent)
    int height() const { return depth_.height; }
    GBufferView view() const;
    // Lets go of the picture: the decoder may reuse it (colour stays).
    void release();

private:
    friend class Decoder;
    std::shared_ptr<const void> picture_;
    ImageView<const float> depth_;
    ImageView<const glm::vec2> motion_;
    Image<float> repaired_depth_;
    Image<glm::vec2> repaired_motion_;
};

class Decoder {
public:
    Decoder();  // default options
    // Checks the options (max_pixels >= 1), then makes `decoder` a new decoder with them; on an
    // error it is left as it was.
    static Status create(const DecoderOptions& options, Decoder& decoder);
    ~Decoder();
    Decoder(Decoder&&) noexcept;
    Decoder& operator=(Decoder&&) noexcept;

    // Takes one whole packet (header + payload). A bad packet is an error Status naming the
    // field; the decoder stays usable and resumes at the next decodable frame.
    Status send_packet(std::span<const uint8_t> packet);
    // Ok with the next decoded frame in `frame`, or NeedMoreData: send the next packet first.
    // The frame's colour buffer goes back to the decoder for a later frame (no allocation per
    // frame); its picture is let go.
    Result receive_frame(DecodedFrame& frame);
    // The same into a Frame that owns its channels: depth and motion are copied (with
    // DecoderOptions::display the Frame gets no colour: take the DecodedFrame's `display`).
    Result receive_frame(Frame& frame);
    void flush();

    const StreamStats& stats() const;

    struct State;

private:
    friend class Encoder;  // Encoder::resume takes the references it decoded
    std::unique_ptr<State> state_;
};

// What DepthMode::View promises, measured: decoded and true depth of one frame seen by `camera`
// (perspective), each pixel reprojected into cameras translated by `displacement` scene units in
// 28 directions (the 26 of a cube's faces, edges and corners, and the two the pixel is most
// sensitive to); pixels the moved camera does not see in front of it are left out.
struct ViewDepthError {
    double max_px = 0.0;                    // largest distance between the two reprojections
    std::size_t background_mismatches = 0;  // +inf in one and not the other
    std::size_t pixels = 0;                 // pixels with finite depth in both
    std::size_t pixels_over_bound = 0;      // of those, moved by more than `bound_px`
};
ViewDepthError measure_view_depth_error(const Camera& camera, ImageView<const float> truth,
                                        ImageView<const float> decoded, float displacement,
                                        float bound_px = INFINITY);
// The 1/z step DepthMode::View uses for frames of this size seen through `projection`.
float view_depth_step(const glm::mat4& projection, int width, int height, float error_px,
                      float displacement);

// Checks one packet (length, version, CRC) and reads its header into `info` (data left empty).
Status inspect_packet(std::span<const uint8_t> packet, Packet& info, int64_t& timestamp_us);

// A .rps file: a file header followed by packets (docs/bitstream.md).
Status write_stream_header(std::vector<uint8_t>& out, int width, int height, double fps);
struct StreamInfo {
    int width = 0, height = 0;
    double fps = 0.0;
};
// A stretch of a .rps file that does not hold a whole valid packet (docs/bitstream.md,
// "Damaged files").
struct StreamDamage {
    std::size_t offset = 0;  // of its first byte in the file
    std::size_t bytes = 0;   // skipped
    std::string reason;      // why the bytes at `offset` are not a packet
};
// Splits a whole .rps file into its packets, each checked as send_packet checks its header
// (fields, length, CRC). After damage it resynchronises on the next byte where a whole valid
// packet starts; every skipped stretch goes to `damage`. An error only for a bad file header.
Status split_stream(std::span<const uint8_t> file, StreamInfo& info,
                    std::vector<std::span<const uint8_t>>& packets,
                    std::vector<StreamDamage>& damage);
// The same, stopping at the first damage: an error naming it, with `packets` holding the whole
// packets before it (a torn tail, say).
Status split_stream(std::span<const uint8_t> file, StreamInfo& info,
                    std::vector<std::span<const uint8_t>>& packets);

// Frames first..last (or first and every later one when `open`) that a damaged file lost.
struct LostFrames {
    uint32_t first = 0, last = 0;
    bool open = false;
    std::string reason;  // "in the damaged bytes", "reference not decoded", a decoder error
};
// What decode_stream found.
struct StreamReport {
    std::vector<StreamDamage> damage;
    std::vector<LostFrames> lost;
    std::size_t packets = 0;  // whole packets found
    std::size_t frames = 0;   // frames decoded
    bool ok() const { return damage.empty() && lost.empty(); }
    // One line: the bytes skipped (where, why) and the frames not decoded (which, why).
    std::string summary() const;
};
// Decodes every frame of a .rps file that damage leaves decodable: `sink` gets each one with
// its frame number, in stream order. A frame whose reference was lost is skipped (and listed)
// until the next key frame or a frame whose reference is held. An error for a bad file header
// or from the sink; the losses are in `report`.
using FrameSink = std::function<Status(uint32_t frame, Frame& decoded)>;
Status decode_stream(std::span<const uint8_t> file, Decoder& decoder, StreamInfo& info,
                     StreamReport& report, const FrameSink& sink);

}  // namespace reprise::codec
