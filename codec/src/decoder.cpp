// Decoder: checks each packet (length, CRC, parameters, reference held), decodes into a scratch
// picture and only then commits it, so a bad packet leaves the decoder as it was.
#include <algorithm>
#include <deque>

#include "decoder_state.hpp"
#include "internal.hpp"
#include "reprise/core/byte_io.hpp"

namespace reprise::codec {

namespace {

constexpr std::size_t kMaxQueuedFrames = 16;

template <class T>
Image<T> take_spare(std::vector<Image<T>>& spare) {
    if (spare.empty()) return {};
    Image<T> buffer = std::move(spare.back());
    spare.pop_back();
    return buffer;
}

// The caller's buffer comes back for a later frame (no allocation per frame); one the caller
// moved from keeps its size but not its pixels, and is not reused.
template <class T>
void hand_out(Image<T>& made, Image<T>& callers, std::vector<Image<T>>& spare,
              const SequenceParams& sp) {
    std::swap(callers, made);
    if (made.width() == sp.width && made.height() == sp.height &&
        made.pixel_count() == std::size_t(sp.width) * std::size_t(sp.height) && spare.size() < 2)
        spare.push_back(std::move(made));
}

}  // namespace

Decoder::Decoder() : state_(std::make_unique<State>()) {}

Status Decoder::create(const DecoderOptions& options, Decoder& decoder) {
    if (options.max_pixels < 1)
        return Status::error("decoder option max_pixels " + std::to_string(options.max_pixels) +
                             ": expected at least 1");
    Decoder made;
    made.state_->options = options;
    decoder = std::move(made);
    return {};
}
Decoder::~Decoder() = default;
Decoder::Decoder(Decoder&&) noexcept = default;
Decoder& Decoder::operator=(Decoder&&) noexcept = default;

Status Decoder::send_packet(std::span<const uint8_t> packet) {
    State& s = *state_;
    PacketHeader h;
    std::span<const uint8_t> payload;
    REPRISE_TRY(parse_packet(packet, h, payload));
    const std::string where = "frame " + std::to_string(h.frame);
    if (s.queue.size() >= kMaxQueuedFrames)
        return Status::error(where + ": " + std::to_string(s.queue.size()) +
                             " decoded frames not taken by receive_frame");
    const bool key = h.type == PacketType::Key;
    if (!key && s.have_newest && h.frame <= s.newest)
        return Status::error(where + ": not newer than frame " + std::to_string(s.newest) +
                             " (duplicate or late)");
    ByteReader r(payload, where);
    SequenceParams sp = s.sp;
    if (key) {
        REPRISE_TRY(read_params(r, sp));
        if (int64_t(sp.width) * sp.height > s.options.max_pixels)
            return Status::error(where + ": " + std::to_string(sp.width) + "x" +
                                 std::to_string(sp.height) +
                                 " is more than this decoder's limit of " +
                                 std::to_string(s.options.max_pixels) + " pixels");
    } else if (!s.started) {
        return Status::error(where + ": inter frame before any key frame");
    }
    const Picture* ref = nullptr;
    if (!key) {
        const int slot = s.slot_of(h.reference);
        if (slot < 0)
            return Status::error(where + ": reference frame " + std::to_string(h.reference) +
                                 " is not held");
        ref = s.refs[slot].get();
    }
    std::span<const uint8_t> sections[4];
    for (auto& section : sections) section = r.bytes(r.varint());
    if (!r.ok()) return Status::error(r.error());
    if (r.remaining())
        return Status::error(where + ": " + std::to_string(r.remaining()) +
                             " bytes after the last section");

    Picture& pic = *s.scratch;
    FrameContext fc{&sp, ref, key, &s.work};
    fc.models = &pic.models;
    StreamStats fs;
    Camera camera;
    double time = 0.0;
    std::vector<ObjectMotion> objects;
    std::size_t object_bytes = 0;
    REPRISE_TRY(
        decode_camera(sections[0], ref, camera, time, sp.width, sp.height, objects, object_bytes));
    fc.objects = objects;
    pic.objects = objects;
    fs.motion_bits += 8 * object_bytes;
    fs.motion_objects = objects.size();
    REPRISE_TRY(decode_depth(fc, camera, sections[1], pic.depth, fs));
    ImageView<const glm::vec2> motion;
    {
        const StageTimer timer(fs.ms.motion);
        REPRISE_TRY(
            decode_motion(fc, camera, pic.depth.view(), sections[2], pic.motion, pic.owner, fs));
        motion = motion_to_reference(sp, camera, pic.depth, pic.motion, ref, h.frame, s.work);
    }
    fs.older_reference = ref && ref->frame + 1 != h.frame;
    REPRISE_TRY(decode_color(fc, pic.depth.view(), motion, sections[3], pic.planes, fs));
    fs.camera_bits += 8 * (sections[0].size() - object_bytes);
    fs.frames = 1;
    fs.key_frames = key;
    fs.header_bits =
        8 * packet.size() - (fs.camera_bits + fs.depth_bits + fs.motion_bits + fs.color_bits);

    // Commit: the picture takes the oldest (or a free) slot; a key frame drops the rest.
    pic.camera = camera;
    pic.time = time;
    pic.frame = h.frame;
    pic.held = true;
    if (key) {
        for (auto& p : s.refs) p->held = false;
        s.sp = sp;
        s.started = true;
    }
    const int slot = replacement_slot(s.refs, h.kept ? int64_t(h.frame) - h.kept : -1);
    std::swap(s.refs[slot], s.scratch);
    // The picture replaced is the next one decoded into, unless a frame handed out still reads it.
    if (s.scratch.use_count() > 1) s.scratch = std::make_shared<Picture>();
    s.have_newest = true;
    s.newest = h.frame;

    State::Output out{.picture = s.refs[slot], .fps = s.sp.fps};
    {
        const StageTimer timer(fs.ms.convert);
        const ImageView<const float> depth = out.picture->depth.view();
        if (s.options.color && s.options.display) {
            out.display = take_spare(s.spare_display);
            display_from_planes(out.picture->planes, s.sp, depth, out.display);
        } else if (s.options.color) {
            out.color = take_spare(s.spare);
            linear_from_planes(out.picture->planes, s.sp, depth, out.color);
        }
    }
    s.queue.push_back(std::move(out));
    add_stats(s.stats, fs);
    return {};
}

GBufferView DecodedFrame::view() const {
    return {
        .color = color.view(), .depth = depth_, .motion = motion_, .camera = camera, .fps = fps};
}

void DecodedFrame::release() {
    picture_.reset();
    depth_ = {}, motion_ = {};
}

Result Decoder::receive_frame(DecodedFrame& frame) {
    State& s = *state_;
    if (s.queue.empty()) return Result::NeedMoreData;
    State::Output& out = s.queue.front();
    hand_out(out.color, frame.color, s.spare, s.sp);
    hand_out(out.display, frame.display, s.spare_display, s.sp);
    const Picture& pic = *out.picture;
    frame.camera = pic.camera;
    frame.fps = out.fps;
    frame.depth_ = pic.depth.view();
    frame.motion_ = pic.motion.view();
    frame.picture_ = std::move(out.picture);
    s.queue.pop_front();
    // A stream can spell NaN (lossless depth keeps float bits): repaired in copies, so the
    // references stay the encoder's. Colour comes from a table of finite values: not scanned.
    GBufferView scanned = frame.view();
    scanned.color = {};
    NonfiniteCounts counts = count_nonfinite(scanned);
    if (counts.depth) {
        frame.repaired_depth_.assign(frame.depth_);
        s.repair.repair_depth(frame.repaired_depth_.view());
        frame.depth_ = frame.repaired_depth_.view();
    }
    if (counts.motion) {
        frame.repaired_motion_.assign(frame.motion_);
        s.repair.repair_motion(frame.repaired_motion_.view());
        frame.motion_ = frame.repaired_motion_.view();
    }
    counts.frames = counts.total() > 0;
    s.stats.nonfinite += counts;
    return Result::Ok;
}

Result Decoder::receive_frame(Frame& frame) {
    DecodedFrame& d = state_->as_frame;
    const Result result = receive_frame(d);
    if (!result) return result;
    std::swap(frame.color, d.color);
    frame.depth.assign(d.depth());
    frame.motion.assign(d.motion());
    frame.normal.clear();
    frame.id.clear();
    frame.camera = d.camera;
    frame.fps = d.fps;
    d.release();
    return result;
}

void Decoder::flush() {}

const StreamStats& Decoder::stats() const { return state_->stats; }

}  // namespace reprise::codec
