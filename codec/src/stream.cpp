// A whole .rps file decoded as far as damage allows, and what it lost (docs/bitstream.md,
// "Damaged files").
#include <map>

#include "internal.hpp"

namespace reprise::codec {

namespace {

constexpr const char* kInDamage = "in the damaged bytes";
constexpr const char* kNoReference = "reference not decoded";

// Lost frames, merged into runs of one reason, and a lookup of whether a frame was lost.
class Losses {
public:
    explicit Losses(std::vector<LostFrames>& out) : out_(out) {}
    void add(uint32_t first, uint32_t last, bool open, const std::string& reason) {
        LostFrames* back = out_.empty() ? nullptr : &out_.back();
        if (back && !back->open && !open && back->last + 1 == first && back->reason == reason)
            back->last = last;
        else
            out_.push_back({first, last, open, reason});
        uint32_t& end = ranges_[first];
        end = std::max(end, open ? UINT32_MAX : last);
    }
    bool contains(uint32_t frame) const {
        auto it = ranges_.upper_bound(frame);
        return it != ranges_.begin() && std::prev(it)->second >= frame;
    }

private:
    std::vector<LostFrames>& out_;
    std::map<uint32_t, uint32_t> ranges_;
};

std::string frames_text(const LostFrames& l) {
    if (l.open) return l.first ? "after " + std::to_string(l.first - 1) : "all";
    if (l.first == l.last) return std::to_string(l.first);
    return std::to_string(l.first) + "-" + std::to_string(l.last);
}

}  // namespace

Status decode_stream(std::span<const uint8_t> file, Decoder& decoder, StreamInfo& info,
                     StreamReport& report, const FrameSink& sink) {
    report = {};
    std::vector<std::span<const uint8_t>> packets;
    REPRISE_TRY(split_stream(file, info, packets, report.damage));
    report.packets = packets.size();
    Losses losses(report.lost);
    const auto offset = [&](std::span<const uint8_t> p) {
        return std::size_t(p.data() - file.data());
    };
    std::size_t damage = 0;
    bool seen = false;  // a packet before this one
    uint32_t previous = 0;
    Frame frame;
    for (const auto& packet : packets) {
        bool damaged = false;
        for (; damage < report.damage.size() && report.damage[damage].offset < offset(packet);
             ++damage)
            damaged = true;
        PacketHeader h;
        std::span<const uint8_t> payload;
        REPRISE_TRY(parse_packet(packet, h, payload));  // split_stream checked it
        const uint32_t from = seen ? previous + 1 : 0;
        if (damaged && h.frame > from && (!seen || h.frame > previous))
            losses.add(from, h.frame - 1, false, kInDamage);
        seen = true;
        previous = h.frame;
        const Status s = decoder.send_packet(packet);
        if (!s.ok()) {
            const bool orphan = h.type == PacketType::Inter && losses.contains(h.reference);
            losses.add(h.frame, h.frame, false, orphan ? kNoReference : s.message());
        }
        while (decoder.receive_frame(frame) == Result::Ok) {
            ++report.frames;
            REPRISE_TRY(sink(h.frame, frame));
        }
    }
    if (damage < report.damage.size()) {
        if (!seen)
            losses.add(0, 0, true, kInDamage);
        else if (previous < UINT32_MAX)
            losses.add(previous + 1, 0, true, kInDamage);
    }
    return {};
}

std::string StreamReport::summary() const {
    constexpr std::size_t kShown = 4;
    std::string line;
    if (!damage.empty()) {
        std::size_t bytes = 0;
        for (const StreamDamage& d : damage) bytes += d.bytes;
        line = "damaged stream: " + std::to_string(bytes) + " bytes skipped";
        for (std::size_t i = 0; i < damage.size() && i < kShown; ++i)
            line += std::string(i ? ", " : ": ") + std::to_string(damage[i].bytes) + " at byte " +
                    std::to_string(damage[i].offset) + " (" + damage[i].reason + ")";
        if (damage.size() > kShown)
            line += " and " + std::to_string(damage.size() - kShown) + " more stretches";
    }
    if (!lost.empty()) {
        line += std::string(line.empty() ? "" : "; ") + "frames not decoded";
        for (std::size_t i = 0; i < lost.size() && i < kShown; ++i)
            line +=
                std::string(i ? ", " : ": ") + frames_text(lost[i]) + " (" + lost[i].reason + ")";
        if (lost.size() > kShown)
            line += " and " + std::to_string(lost.size() - kShown) + " more runs";
    }
    line += std::string(line.empty() ? "" : "; ") + std::to_string(frames) + " frames decoded";
    return line;
}

}  // namespace reprise::codec
