// Packet header, key frame parameters and the .rps file container (docs/bitstream.md).
#include <algorithm>

#include "crc32c.hpp"
#include "internal.hpp"
#include "reprise/core/byte_io.hpp"

namespace reprise::codec {

int default_slices(int height) {
    // One slice per 24 macroblock rows (720p: 2, 1080p: 3, 2160p: 6): each slice learns its own
    // statistics (key frames from 1/2, inter frames from their reference's, version 20); with
    // models starting at 1/2 in every frame, one per 8 rows cost 3-5 % of an inter frame at
    // 1280x720, and the two cores' tasks ran no faster at 1080p.
    const int mb_rows = (height + kMb - 1) / kMb;
    return std::clamp((mb_rows + 23) / 24, 1, kMaxSlices);
}

namespace {

// The header's fields up to the payload (docs/bitstream.md section 2); `length` is the payload's.
Status read_header(ByteReader& r, PacketHeader& h, uint64_t& length) {
    const uint32_t magic = r.u32();
    const uint8_t version = r.u8();
    const uint8_t type = r.u8();
    if (!r.ok()) return Status::error(r.error());
    // Magic and version first: an older stream's fixed fields do not read as varints.
    if (magic != kPacketMagic)
        return Status::error("packet header: bad magic (not a reprise packet)");
    if (version != kVersion)
        return Status::error("packet header: version " + std::to_string(version) +
                             " (this decoder reads " + std::to_string(kVersion) +
                             "; re-encode the stream)");
    if (type > uint8_t(PacketType::Inter))
        return Status::error("packet header: unknown type " + std::to_string(type));
    const uint64_t frame = r.varint(), distance = r.varint(), kept = r.varint();
    h.timestamp_us = unzigzag(r.varint());
    length = r.varint();
    if (!r.ok()) return Status::error(r.error());
    if (r.position() > kMaxPacketHeader)
        return Status::error("packet header: " + std::to_string(r.position()) + " bytes (at most " +
                             std::to_string(kMaxPacketHeader) + ")");
    if (frame > 0xFFFFFFFFu)
        return Status::error("packet header: frame number " + std::to_string(frame) +
                             " above 2^32 - 1");
    h.type = PacketType(type);
    h.frame = uint32_t(frame);
    if (h.type == PacketType::Key ? distance != 0 : distance == 0 || distance > frame)
        return Status::error("packet header: frame " + std::to_string(frame) +
                             (h.type == PacketType::Key
                                  ? " is a key frame and names a reference"
                                  : " names reference distance " + std::to_string(distance)));
    h.reference = uint32_t(frame - distance);
    if (kept > 0 && (h.type == PacketType::Key || kept > frame || kept > 0xFFFF))
        return Status::error(
            "packet header: frame " + std::to_string(frame) + " keeps frame " +
            std::to_string(int64_t(frame) - int64_t(std::min<uint64_t>(kept, uint64_t(1) << 40))) +
            (h.type == PacketType::Key ? " (a key frame keeps none)" : ""));
    h.kept = uint16_t(kept);
    if (length > kMaxPayload)
        return Status::error("packet header: payload length " + std::to_string(length) +
                             " above the maximum");
    return {};
}

}  // namespace

void write_packet(const PacketHeader& h, std::span<const uint8_t> payload,
                  std::vector<uint8_t>& out) {
    out.clear();
    ByteWriter w(out);
    w.u32(kPacketMagic);
    w.u8(kVersion);
    w.u8(uint8_t(h.type));
    w.varint(h.frame);
    w.varint(h.frame - h.reference);
    w.varint(h.kept);
    w.varint(zigzag(h.timestamp_us));
    w.varint(payload.size());
    w.bytes(payload);
    w.u32(crc32c(out, 0));
}

bool reseal_packet(std::vector<uint8_t>& packet) {
    ByteReader r(packet, "packet header");
    const uint32_t magic = r.u32();
    const uint8_t version = r.u8(), type = r.u8();
    uint64_t fields[4];
    for (uint64_t& f : fields) f = r.varint();
    (void)r.varint();  // the payload length, written again
    if (!r.ok()) return false;
    const std::size_t end =
        std::max(r.position(), packet.size() - std::min<std::size_t>(4, packet.size()));
    const std::vector<uint8_t> payload(packet.begin() + std::ptrdiff_t(r.position()),
                                       packet.begin() + std::ptrdiff_t(end));
    packet.clear();
    ByteWriter w(packet);
    w.u32(magic);
    w.u8(version);
    w.u8(type);
    for (uint64_t f : fields) w.varint(f);
    w.varint(payload.size());
    w.bytes(payload);
    w.u32(crc32c(packet, 0));
    return true;
}

Status parse_packet(std::span<const uint8_t> packet, PacketHeader& h,
                    std::span<const uint8_t>& payload) {
    ByteReader r(packet, "packet header");
    uint64_t length = 0;
    REPRISE_TRY(read_header(r, h, length));
    if (r.remaining() < 4 || length != r.remaining() - 4)
        return Status::error("packet header: payload length " + std::to_string(length) + " but " +
                             std::to_string(r.remaining() < 4 ? 0 : r.remaining() - 4) +
                             " bytes follow before the CRC");
    payload = r.bytes(length);
    const uint32_t crc = r.u32();
    if (crc != crc32c(packet.first(packet.size() - 4), 0))
        return Status::error("packet " + std::to_string(h.frame) + ": CRC mismatch");
    return {};
}

Status inspect_packet(std::span<const uint8_t> packet, Packet& info, int64_t& timestamp_us) {
    PacketHeader h;
    std::span<const uint8_t> payload;
    REPRISE_TRY(parse_packet(packet, h, payload));
    info.data.clear();
    info.frame = h.frame;
    info.reference = h.reference;
    info.type = h.type;
    timestamp_us = h.timestamp_us;
    return {};
}

void write_params(const SequenceParams& sp, std::vector<uint8_t>& out) {
    ByteWriter w(out);
    w.u16(uint16_t(sp.width));
    w.u16(uint16_t(sp.height));
    w.u8(uint8_t(sp.chroma));
    w.u8(uint8_t(sp.depth));
    w.f32(sp.depth_error);
    if (sp.depth == DepthMode::View) {
        w.f32(sp.view_error);
        w.f32(sp.view_displacement);
        w.f32(sp.view_step);
    }
    w.f32(sp.motion_error);
    w.u8(uint8_t(sp.slices));
    w.f64(sp.fps);
}

Status read_params(ByteReader& r, SequenceParams& sp) {
    sp.width = r.u16();
    sp.height = r.u16();
    const uint8_t chroma = r.u8(), depth = r.u8();
    sp.depth_error = r.f32();
    if (depth == uint8_t(DepthMode::View)) {
        sp.view_error = r.f32();
        sp.view_displacement = r.f32();
        sp.view_step = r.f32();
    }
    sp.motion_error = r.f32();
    sp.slices = r.u8();
    sp.fps = r.f64();
    if (!r.ok()) return Status::error(r.error());
    REPRISE_TRY(check_image_size(sp.width, sp.height, "key frame parameters"));
    if (chroma > uint8_t(Chroma::C444))
        return Status::error("key frame parameters: unknown chroma format " +
                             std::to_string(chroma));
    if (depth > uint8_t(DepthMode::View))
        return Status::error("key frame parameters: unknown depth mode " + std::to_string(depth));
    sp.chroma = Chroma(chroma);
    sp.depth = DepthMode(depth);
    if (sp.depth == DepthMode::Bounded && !(sp.depth_error >= 1e-7f && sp.depth_error <= 0.1f))
        return Status::error("key frame parameters: depth error bound outside 1e-7..0.1");
    if (sp.depth == DepthMode::View && !(sp.view_step >= 1e-12f && sp.view_step <= 1e6f))
        return Status::error("key frame parameters: inverse depth step outside 1e-12..1e6");
    if (sp.depth == DepthMode::View && !(sp.view_error >= 1e-3f && sp.view_error <= 100.0f))
        return Status::error("key frame parameters: view bound outside 0.001..100 px");
    if (!(sp.motion_error == 0.0f ||
          (sp.motion_error >= kMinMotionError && sp.motion_error <= 8.0f)))
        return Status::error("key frame parameters: motion error bound outside 0.1..8 px (or 0)");
    if (sp.slices < 1 || sp.slices > std::min(kMaxSlices, sp.mb_rows()))
        return Status::error("key frame parameters: " + std::to_string(sp.slices) + " slices for " +
                             std::to_string(sp.mb_rows()) + " macroblock rows");
    if (!(sp.fps >= 0.0 && sp.fps <= 1000.0))
        return Status::error("key frame parameters: frame rate outside 0..1000");
    return {};
}

Status write_stream_header(std::vector<uint8_t>& out, int width, int height, double fps) {
    REPRISE_TRY(check_image_size(width, height, "stream header"));
    ByteWriter w(out);
    w.u32(kFileMagic);
    w.u8(kVersion);
    w.u8(0);
    w.u16(0);
    w.u32(uint32_t(width));
    w.u32(uint32_t(height));
    w.f64(fps);
    return {};
}

namespace {

// Why the bytes at `at` do not start a whole valid packet; empty when they do (its size then in
// `size`). A CRC check is charged to `budget`.
std::string packet_at(std::span<const uint8_t> file, std::size_t at, std::size_t& size,
                      std::size_t& budget) {
    const std::size_t remaining = file.size() - at;
    const uint8_t magic[4] = {'R', 'P', 'K', 'T'};
    if (!std::equal(file.begin() + std::ptrdiff_t(at),
                    file.begin() + std::ptrdiff_t(at + std::min<std::size_t>(remaining, 4)), magic))
        return "no packet header (bad magic)";
    ByteReader r(file.subspan(at, std::min(remaining, kMaxPacketHeader)), "packet header");
    PacketHeader header;
    uint64_t length = 0;
    if (const Status s = read_header(r, header, length); !s.ok())
        return !r.ok() && remaining < kMaxPacketHeader ? "the file ends inside a packet header (" +
                                                             std::to_string(remaining) + " bytes)"
                                                       : s.message();
    const std::size_t after = remaining - r.position();
    if (after < 4 || length > after - 4)
        return "packet header of frame " + std::to_string(header.frame) +
               ": runs past the end of the file (payload length " + std::to_string(length) + ", " +
               std::to_string(after < 4 ? 0 : after - 4) + " bytes follow before a CRC)";
    size = r.position() + std::size_t(length) + 4;
    budget -= std::min(budget, size);
    PacketHeader h;
    std::span<const uint8_t> payload;
    const Status s = parse_packet(file.subspan(at, size), h, payload);
    return s.ok() ? std::string() : s.message();
}

// The first offset from `from` where the packet magic starts, else the file's size.
std::size_t find_magic(std::span<const uint8_t> file, std::size_t from) {
    const uint8_t magic[4] = {'R', 'P', 'K', 'T'};
    const auto it = std::search(file.begin() + std::ptrdiff_t(std::min(from, file.size())),
                                file.end(), std::begin(magic), std::end(magic));
    return std::size_t(it - file.begin());
}

}  // namespace

Status split_stream(std::span<const uint8_t> file, StreamInfo& info,
                    std::vector<std::span<const uint8_t>>& packets,
                    std::vector<StreamDamage>& damage) {
    packets.clear();
    damage.clear();
    ByteReader r(file, "stream");
    const uint32_t magic = r.u32();
    const uint8_t version = r.u8();
    const uint8_t reserved8 = r.u8();
    const uint16_t reserved16 = r.u16();
    info.width = int(r.u32());
    info.height = int(r.u32());
    info.fps = r.f64();
    if (!r.ok()) return Status::error(r.error());
    if (magic != kFileMagic) return Status::error("stream: not a reprise stream (bad magic)");
    if (version != kVersion)
        return Status::error("stream: version " + std::to_string(version) + " (this reader reads " +
                             std::to_string(kVersion) + "; re-encode the stream)");
    if (reserved8 || reserved16)
        return Status::error("stream: reserved header bytes 5..7 are not 0");
    REPRISE_TRY(check_image_size(info.width, info.height, "stream header"));
    // Candidates that pass the cheap header checks cost a CRC over their claimed length: a file
    // of false headers gets this much CRC work (a few times its size) before the walk gives up.
    std::size_t budget = 4 * file.size() + (std::size_t(1) << 20);
    std::size_t at = r.position();
    while (at < file.size()) {
        std::size_t size = 0;
        std::string why = packet_at(file, at, size, budget);
        if (why.empty()) {
            packets.push_back(file.subspan(at, size));
            at += size;
            continue;
        }
        std::size_t next = at + 1;
        for (;; ++next) {
            next = find_magic(file, next);
            if (next == file.size()) break;
            if (budget == 0) {
                why += "; gave up looking for the next packet (too many false packet headers)";
                next = file.size();
                break;
            }
            if (packet_at(file, next, size, budget).empty()) break;
        }
        damage.push_back({at, next - at, std::move(why)});
        at = next;
    }
    return {};
}

Status split_stream(std::span<const uint8_t> file, StreamInfo& info,
                    std::vector<std::span<const uint8_t>>& packets) {
    std::vector<StreamDamage> damage;
    REPRISE_TRY(split_stream(file, info, packets, damage));
    if (damage.empty()) return {};
    const StreamDamage& first = damage.front();
    std::erase_if(packets, [&](std::span<const uint8_t> p) {
        return std::size_t(p.data() - file.data()) > first.offset;
    });
    return Status::error("stream: byte " + std::to_string(first.offset) + ": " + first.reason);
}

}  // namespace reprise::codec
