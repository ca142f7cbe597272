#pragma once
// What encoder and decoder share: stream parameters, the reference picture, per-stage entry points.
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "motion_models.hpp"
#include "range_coder.hpp"
#include "reprise/codec/codec.hpp"
#include "reprise/core/byte_io.hpp"
#include "slices.hpp"

namespace reprise::codec {

inline constexpr uint32_t kPacketMagic = 0x544B5052;  // "RPKT"
inline constexpr uint32_t kFileMagic = 0x53525052;    // "RPRS"
inline constexpr uint8_t kVersion = 20;
// Signed integers as unsigned varints: 0, -1, 1, -2, ... as 0, 1, 2, 3, ...
inline uint64_t zigzag(int64_t v) { return (uint64_t(v) << 1) ^ uint64_t(v >> 63); }
inline int64_t unzigzag(uint64_t u) { return int64_t(u >> 1) ^ -int64_t(u & 1); }

// The longest packet header: magic, version, type and five varints (the CRC follows the payload).
inline constexpr std::size_t kMaxPacketHeader = 6 + 5 + 5 + 3 + 10 + 5;
inline constexpr std::size_t kMaxPayload = 256u << 20;
inline constexpr int kMaxSide = 16384;
inline constexpr int kMaxSlices = 64;
inline constexpr int kReferences = 4;           // pictures both sides keep
inline constexpr int kMb = 16;                  // macroblock: 16x16 luma
inline constexpr float kMinMotionError = 0.1f;  // above a pixel value's 1/8 px rounding

struct SequenceParams {
    int width = 0, height = 0;
    Chroma chroma = Chroma::C420;
    DepthMode depth = DepthMode::Lossless;
    float depth_error = 1e-4f;
    // DepthMode::View: the bound E (px) and displacement B it was derived from (informative) and
    // the 1/z quantiser step the codes use.
    float view_error = 0.25f, view_displacement = 0.164f, view_step = 0.0f;
    // Largest distance (px) between decoded and source motion; 0 = per pixel to 1/8 px.
    float motion_error = 0.25f;
    int slices = 1;
    double fps = 0.0;
    bool operator==(const SequenceParams&) const = default;

    // Real chroma extent (the planes are padded to whole macroblocks beyond it).
    int chroma_width() const { return chroma == Chroma::C420 ? (width + 1) / 2 : width; }
    int chroma_height() const { return chroma == Chroma::C420 ? (height + 1) / 2 : height; }
    int mb_cols() const { return (width + kMb - 1) / kMb; }
    int mb_rows() const { return (height + kMb - 1) / kMb; }
    // Chroma subsampling shift of plane k (0 = Y, 1 = Co, 2 = Cg).
    int shift(int k) const { return k > 0 && chroma == Chroma::C420 ? 1 : 0; }
    int plane_width(int k) const { return (mb_cols() * kMb) >> shift(k); }
    int plane_height(int k) const { return (mb_rows() * kMb) >> shift(k); }
    // Slice s covers macroblock rows [slice_begin(s), slice_begin(s + 1)).
    int slice_begin(int s) const { return int(int64_t(mb_rows()) * s / slices); }
    // log2 step of the bounded depth quantiser: relative error of z at most depth_error.
    double depth_step() const;
};

// 8-bit display colour as YCoCg-R planes (Y 0..255, Co and Cg -255..255), padded to whole
// macroblocks by repeating the last row and column.
struct Planes {
    Image<int16_t> p[3];
};

// What both sides hold of a decoded frame.
struct Picture {
    uint32_t frame = 0;
    bool held = false;
    Planes planes;
    Image<float> depth;       // decoded depth (empty when the stream has none)
    Image<glm::vec2> motion;  // decoded backward motion to the previous frame
    Image<uint32_t> owner;    // per pixel: the id of the object whose motion it took, else 0
    std::vector<ObjectMotion> objects;  // the rigid object motions its packet sent
    Camera camera;
    double time = 0.0;
    // Each section's adaptive models at the end of its slices (version 20, ModelCarry).
    struct Models {
        SliceModels depth, motion, colour;
    } models;
};

// --- packet.cpp: the packet header and CRC (docs/bitstream.md) and the key frame's parameters.
struct PacketHeader {
    PacketType type = PacketType::Key;
    uint32_t frame = 0, reference = 0;
    int64_t timestamp_us = 0;
    uint16_t kept = 0;  // this picture replaces none with frame number frame - kept (0: none)
};
void write_packet(const PacketHeader& header, std::span<const uint8_t> payload,
                  std::vector<uint8_t>& out);
Status parse_packet(std::span<const uint8_t> packet, PacketHeader& header,
                    std::span<const uint8_t>& payload);
// A packet whose bytes were changed, with its payload length and CRC made to fit again (tests,
// fuzzing): the bytes between the header and the last four are the payload. False when the
// header's fields do not read.
bool reseal_packet(std::vector<uint8_t>& packet);
void write_params(const SequenceParams& sp, std::vector<uint8_t>& out);
Status read_params(ByteReader& r, SequenceParams& sp);
int default_slices(int height);

struct Workspace;

// Adds the milliseconds from its making to its end to `into` (StreamStats::ms).
class StageTimer {
public:
    explicit StageTimer(double& into) : into_(into) {}
    ~StageTimer() {
        into_ += std::chrono::duration<double, std::milli>(Clock::now() - start_).count();
    }
    StageTimer(const StageTimer&) = delete;
    StageTimer& operator=(const StageTimer&) = delete;

private:
    using Clock = std::chrono::steady_clock;
    double& into_;
    Clock::time_point start_ = Clock::now();
};

// Held pictures: values in the encoder, shared with the frames handed out in the decoder.
inline const Picture& held(const Picture& p) { return p; }
inline const Picture& held(const std::shared_ptr<Picture>& p) { return *p; }
// The slot a new picture goes to: a free one, else the picture with the smallest frame number
// other than `kept`.
template <class Held>
int replacement_slot(const Held (&refs)[kReferences], int64_t kept = -1) {
    int slot = -1;
    for (int i = 0; i < kReferences; ++i) {
        const Picture& p = held(refs[i]);
        if (!p.held) return i;
        if (int64_t(p.frame) != kept && (slot < 0 || p.frame < held(refs[slot]).frame)) slot = i;
    }
    return slot;
}
// The slot holding frame `frame`, or -1.
template <class Held>
int held_slot(const Held (&refs)[kReferences], uint32_t frame) {
    for (int i = 0; i < kReferences; ++i)
        if (held(refs[i]).held && held(refs[i]).frame == frame) return i;
    return -1;
}

// --- color.cpp
// Linear colour -> 8-bit sRGB -> YCoCg-R, chroma averaged 2x2 for 4:2:0; or from the 8-bit sRGB
// display values themselves (RGBA8, alpha not read).
void planes_from_linear(ImageView<const glm::vec4> color, const SequenceParams& sp, Planes& out);
void planes_from_display(ImageView<const glm::u8vec4> color, const SequenceParams& sp, Planes& out);
// YCoCg-R planes -> linear RGB, or 8-bit sRGB display values (A: coverage from depth, 1 without
// depth).
void linear_from_planes(const Planes& planes, const SequenceParams& sp,
                        ImageView<const float> depth, Image<glm::vec4>& out);
void display_from_planes(const Planes& planes, const SequenceParams& sp,
                         ImageView<const float> depth, Image<glm::u8vec4>& out);

// --- geometry.cpp
// Backward motion that the cameras alone explain: pixel p of a frame seen by `from` with depth z
// lies at p + m in the image of camera `to` (background by its direction). NaN where the point
// is behind `to` or depth is NaN/negative; 0 everywhere when the cameras are identical.
void camera_motion(const Camera& from, ImageView<const float> depth, const glm::mat4& to_view,
                   const glm::mat4& to_projection, ImageView<glm::vec2> out);
// Pixel (x, y) of a width x height picture at depth z in the camera space of `camera`
// (homogeneous, w = 0 for a background direction); false for NaN or negative depth.
bool unproject_pixel(const Camera& camera, int width, int height, int x, int y, float z,
                     glm::vec4& out);
// The clip transform of a point that moved rigidly: `moved` takes its position in the camera
// space of `camera` to where it was one frame earlier (same space); then the previous camera.
glm::mat4 rigid_to_clip(const Camera& camera, const glm::dmat4& moved);
// The motion camera_motion gives, for the pixels of `out` (placed at x0, y0 in the picture) and
// a point transform of rigid_to_clip, pixel by pixel (no row form); with `out_depth`, also each
// point's depth in the camera that `to_camera` (camera space -> its camera space) leads to.
void rigid_motion(const Camera& from, ImageView<const float> depth, const glm::mat4& to_clip,
                  int x0, int y0, ImageView<glm::vec2> out, const glm::mat4& to_camera = {},
                  ImageView<float> out_depth = {});
// The reference depth forward-projected into camera `to` (z-buffered, nearest pixel);
// NaN where nothing landed. A copy when the cameras are identical.
// Pixels whose `owner` id is one of `objects` (this frame's) move with that object's motion.
// `plane_step` > 0 (view mode: the 1/z step q): each landing takes the value of its surface's
// plane at the centre of the pixel it lands in, instead of the value where it landed, and cracks
// and narrow gaps between landings are filled; two landings are one surface when their 1/z differ
// by at most max(kSameSurface of the larger, d plane_step), d their distance in pixels in the
// plane fit and 2 in the crack fill (docs/bitstream.md, section 6).
void reproject_depth(const Camera& from, ImageView<const float> depth, const Camera& to,
                     ImageView<float> out, ImageView<const uint32_t> owner = {},
                     std::span<const ObjectMotion> objects = {}, float plane_step = 0.0f);
// What drives colour prediction: the decoded motion when the reference is the previous frame,
// else the camera motion from this frame to the reference's camera (0 without depth).
ImageView<const glm::vec2> motion_to_reference(const SequenceParams& sp, const Camera& camera,
                                               const Image<float>& depth,
                                               const Image<glm::vec2>& motion,
                                               const Picture* reference, uint32_t frame,
                                               Workspace& work);
// Deterministic log2 / exp2 (IEEE double arithmetic only, no libm).
double exact_log2(double x);
double exact_exp2(double x);

// One pixel's motion residual, in eighths of a pixel.
struct MotionResidual {
    int32_t x = 0, y = 0;
    bool invalid = false;  // decoded motion is NaN although the cameras explain this pixel
    bool zero() const { return !invalid && x == 0 && y == 0; }
};

// Per-frame scratch, sized on the first frame and reused while the size stays the same.
// An inter macroblock's colour encoder decisions, made for the whole frame before its slices are
// coded (color_coder.cpp: they read the source and the prediction only).
struct InterChoice {
    bool skip = false, intra = false;
    uint16_t within = 0;  // bit b: block b (coding order) stays within the skip threshold
    uint16_t quiet = 0;   // bit b: block b's residual quantises to no level (by its SAD)
};

struct Workspace {
    Image<uint32_t> depth_codes, temporal_codes, depth_residuals, depth_predictions;
    Image<uint8_t> depth_shows;  // inter frames: per depth block, what the reprojection shows
    Image<float> projected_depth, view_share;
    Image<glm::vec2> base_motion, to_reference;
    std::vector<MotionResidual> motion_residuals;
    MotionModelScratch motion_models;
    std::vector<ObjectField> object_fields;
    ObjectField cameras_field;        // the memory of the cameras' field while it is not in use
    Image<uint32_t> predicted_owner;  // empty when no pixel is predicted to move with an object
    Image<uint8_t> revealed;          // per luma pixel: the reference did not see it
    std::vector<uint8_t> coded_blocks[3];  // per 8x8 block of each plane: intra or with a residual
    std::vector<InterChoice> inter_choices;  // colour encoder: per macroblock of an inter frame
    std::vector<std::vector<uint8_t>> slice_bytes;
    std::vector<std::vector<uint8_t>> slice_flags;  // per slice: a block row's flags
    std::vector<uint8_t> section;
};

// Sizes an image, keeping its memory (and stale contents) when the size is already right.
template <class T>
void ensure_size(Image<T>& image, int width, int height) {
    if (image.width() != width || image.height() != height) image.resize(width, height);
}

// --- stream sections. Each encoder appends to `out`; each decoder reads one section and returns
// an error naming the field. Stats are added to `stats`.
struct FrameContext {
    const SequenceParams* sp = nullptr;
    const Picture* reference = nullptr;  // null on key frames
    bool key = false;
    Workspace* work = nullptr;
    std::span<const ObjectMotion> objects;  // this frame's, from the camera section
    float view_step = 0.0f;  // encoder, view depth: this frame's step (0: the sequence's)
    // Encoder, view depth: the step the cameras alone ask for, and the source's object ids. A
    // finer step for a fast object is the object's need: the other pixels keep the cameras' bound.
    float camera_step = 0.0f;
    ImageView<const uint32_t> ids;
    Picture::Models* models = nullptr;  // the picture being made: its sections' models

    // Where a section's slices take their models from and leave them (its reference's passed on).
    ModelCarry carry(SliceModels Picture::Models::*section) const {
        const ModelCarry c{key || !reference ? nullptr : &(reference->models.*section),
                           models ? &(models->*section) : nullptr};
        c.pass_on(sp->slices);
        return c;
    }
};

// The camera and the objects' rigid motions (their bytes returned; counted as motion).
std::size_t encode_camera(const Camera& camera, double time, const Picture* reference,
                          std::span<const ObjectMotion> objects, std::vector<uint8_t>& out);
Status decode_camera(std::span<const uint8_t> in, const Picture* reference, Camera& camera,
                     double& time, int width, int height, std::vector<ObjectMotion>& objects,
                     std::size_t& object_bytes);

// Depth: `source` is the input depth (any floats), reconstruction goes to `out`.
void encode_depth(const FrameContext& fc, const Camera& camera, ImageView<const float> source,
                  Image<float>& out, std::vector<uint8_t>& bytes, StreamStats& stats);
Status decode_depth(const FrameContext& fc, const Camera& camera, std::span<const uint8_t> in,
                    Image<float>& out, StreamStats& stats);

// Motion: decoded motion = camera motion + residual (models within sp.motion_error, or per
// pixel in eighths of a pixel when it is 0).
void encode_motion(const FrameContext& fc, const Camera& camera, ImageView<const float> depth,
                   ImageView<const glm::vec2> source, ImageView<const uint32_t> ids,
                   Image<glm::vec2>& out, Image<uint32_t>& owner, std::vector<uint8_t>& bytes,
                   StreamStats& stats);
Status decode_motion(const FrameContext& fc, const Camera& camera, ImageView<const float> depth,
                     std::span<const uint8_t> in, Image<glm::vec2>& out, Image<uint32_t>& owner,
                     StreamStats& stats);

// Colour. `motion` (to the reference) drives the inter prediction; `depth` (this frame's,
// decoded) finds the pixels the reference did not see.
struct ColorEncodeResult {
    std::size_t intra_macroblocks = 0, macroblocks = 0;
};
ColorEncodeResult encode_color(const FrameContext& fc, const Planes& source,
                               ImageView<const float> depth, ImageView<const glm::vec2> motion,
                               int qp, int skip_threshold, Planes& out, std::vector<uint8_t>& bytes,
                               StreamStats& stats);
Status decode_color(const FrameContext& fc, ImageView<const float> depth,
                    ImageView<const glm::vec2> motion, std::span<const uint8_t> in, Planes& out,
                    StreamStats& stats);

// --- deblock.cpp: in-loop filter of the 8x8 edges next to coded blocks.
void deblock(Planes& planes, const std::vector<uint8_t> (&coded)[3], int qp);

// Revealed pixels (docs/bitstream.md section 9): pixels the reference did not see (its depth where
// they land is more than 4 % off theirs) take the prediction of the surface beside them: the
// nearest pixel along their row, within 32 luma pixels, that it saw at the same depth (5 %),
// mirrored about the strip's edge where possible. `revealed` (picture-sized) marks them.
struct Reveal {
    ImageView<const float> depth, reference_depth;
    ImageView<uint8_t> revealed;
};
// Inter prediction of all three planes from the reference by `motion` (Catmull-Rom, integer),
// with `reveal` (when its images are picture-sized) the revealed pixels filled row by row.
// Returns how many luma pixels were revealed.
std::size_t predict_planes(const Planes& reference, const SequenceParams& sp,
                           ImageView<const glm::vec2> motion, Planes& out,
                           const Reveal* reveal = nullptr);
// The same fill alone, over a prediction already made (the reference of the fused pass above).
std::size_t fill_revealed(const SequenceParams& sp, ImageView<const glm::vec2> motion,
                          const Reveal& reveal, Planes& predicted);

}  // namespace reprise::codec
