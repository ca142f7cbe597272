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
        ref = &s.refs[slot];
    }
    std::span<const uint8_t> sections[4];
    for (auto& section : sections) section = r.bytes(r.varint());
    if (!r.ok()) return Status::error(r.error());
    if (r.remaining())
        return Status::error(where + ": " + std::to_string(r.remaining()) +
                             " bytes after the last section");

    FrameContext fc{&sp, ref, key, &s.work};
    Picture& pic = s.scratch;
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
    REPRISE_TRY(
        decode_motion(fc, camera, pic.depth.view(), sections[2], pic.motion, pic.owner, fs));
    const ImageView<const glm::vec2> motion =
        motion_to_reference(sp, camera, pic.depth, pic.motion, ref, h.frame, s.work);
    fs.older_reference = ref && ref->frame + 1 != h.frame;
    REPRISE_TRY(decode_color(fc, motion, sections[3], pic.planes, fs));
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
        for (auto& p : s.refs) p.held = false;
        s.sp = sp;
        s.started = true;
    }
    const int slot = replacement_slot(s.refs, h.kept ? int64_t(h.frame) - h.kept : -1);
    std::swap(s.refs[slot], pic);
    s.have_newest = true;
    s.newest = h.frame;
    add_stats(s.stats, fs);

    const Picture& out = s.refs[slot];
    Frame frame;
    if (!s.spare.empty()) {
        frame = std::move(s.spare.back());
        s.spare.pop_back();
        frame.normal.clear();
        frame.id.clear();
    }
    if (s.options.color)
        linear_from_planes(out.planes, s.sp, out.depth.view(), frame.color);
    else
        frame.color.clear();
    frame.depth = out.depth;
    frame.motion = out.motion;
    frame.camera = out.camera;
    frame.fps = s.sp.fps;
    s.queue.push_back(std::move(frame));
    return {};
}

Result Decoder::receive_frame(Frame& frame) {
    State& s = *state_;
    if (s.queue.empty()) return Result::NeedMoreData;
    std::swap(frame, s.queue.front());
    // A stream can spell NaN (lossless depth keeps float bits): repaired on the way out only,
    // so the references stay the encoder's.
    s.stats.nonfinite += s.repair.repair(frame);
    // The caller's previous buffers come back for the next output (no allocation per frame).
    Frame old = std::move(s.queue.front());
    s.queue.pop_front();
    // A frame the caller moved from keeps its size but not its pixels: not reused.
    auto whole = [&](const auto& image) {
        return image.width() == s.sp.width && image.height() == s.sp.height &&
               image.pixel_count() == std::size_t(s.sp.width) * std::size_t(s.sp.height);
    };
    if ((s.options.color ? whole(old.color) : whole(old.depth)) && s.spare.size() < 2)
        s.spare.push_back(std::move(old));
    return Result::Ok;
}

void Decoder::flush() {}

const StreamStats& Decoder::stats() const { return state_->stats; }

}  // namespace reprise::codec
