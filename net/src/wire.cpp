#include "reprise/net/wire.hpp"

#include <algorithm>
#include <cmath>

namespace reprise::net {

void write_header(Writer& w, const DatagramHeader& header) {
    w.u8(kMagic0);
    w.u8(kMagic1);
    w.u8(kProtocolVersion);
    w.u8(uint8_t(header.type));
    w.u64(header.connection);
}

Status parse_header(std::span<const uint8_t> datagram, DatagramHeader& header) {
    if (datagram.size() > kMaxDatagram)
        return Status::error("datagram: " + std::to_string(datagram.size()) +
                             " bytes, more than 1200");
    Reader r(datagram);
    const uint8_t m0 = r.u8(), m1 = r.u8(), version = r.u8(), type = r.u8();
    header.connection = r.u64();
    if (!r.ok()) return Status::error("datagram: shorter than its 12-byte header");
    if (m0 != kMagic0 || m1 != kMagic1) return Status::error("datagram: bad magic");
    if (version != kProtocolVersion)
        return Status::error("datagram: protocol version " + std::to_string(version) +
                             ", expected 1");
    if (type < 1 || type > uint8_t(DatagramType::Refused))
        return Status::error("datagram: unknown type " + std::to_string(type));
    header.type = DatagramType(type);
    return {};
}

std::size_t encode(const RefusedDatagram& d, std::span<uint8_t> out) {
    Writer w(out);
    write_header(w, {.type = DatagramType::Refused, .connection = d.connection});
    w.u8(uint8_t(d.reason));
    w.u8(d.sessions);
    return w.size();
}

Status parse(std::span<const uint8_t> datagram, RefusedDatagram& d) {
    DatagramHeader h;
    REPRISE_TRY(parse_header(datagram, h));
    if (h.type != DatagramType::Refused || datagram.size() != kRefusedSize)
        return Status::error("refused: not a 14-byte Refused datagram");
    if (datagram[kHeaderSize] != uint8_t(RefusalReason::ServerFull))
        return Status::error("refused: unknown reason " + std::to_string(datagram[kHeaderSize]));
    d.connection = h.connection;
    d.reason = RefusalReason(datagram[kHeaderSize]);
    d.sessions = datagram[kHeaderSize + 1];
    return {};
}

bool valid_scene_name(const std::string& name) {
    if (name.empty() || name.size() > kMaxSceneName) return false;
    for (char c : name)
        if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-'))
            return false;
    return true;
}

namespace {

void write_name(Writer& w, const std::string& name) {
    REPRISE_ASSERT(name.size() <= kMaxSceneName);
    w.u8(uint8_t(name.size()));
    w.bytes({reinterpret_cast<const uint8_t*>(name.data()), name.size()});
}

Status read_name(Reader& r, std::string& name, bool allow_empty, const char* where) {
    const std::size_t n = r.u8();
    auto b = r.bytes(n);
    if (!r.ok()) return Status::error(std::string(where) + ": scene name runs past the end");
    name.assign(reinterpret_cast<const char*>(b.data()), b.size());
    if (name.empty() ? !allow_empty : !valid_scene_name(name))
        return Status::error(std::string(where) + ": scene name is not 1..32 of [a-z0-9_-]");
    return {};
}

Status expect(Reader& r, MessageType type, const char* where) {
    if (r.u8() != uint8_t(type)) return Status::error(std::string(where) + ": wrong message type");
    return {};
}

Status finish(const Reader& r, const char* where) {
    if (!r.ok()) return Status::error(std::string(where) + ": shorter than its fields");
    if (r.remaining() != 0) return Status::error(std::string(where) + ": trailing bytes");
    return {};
}

}  // namespace

std::size_t encode(const StartMessage& m, std::span<uint8_t> out) {
    Writer w(out);
    w.u8(uint8_t(MessageType::Start));
    write_name(w, m.scene);
    return w.size();
}
std::size_t encode(const StreamInfoMessage& m, std::span<uint8_t> out) {
    Writer w(out);
    w.u8(uint8_t(MessageType::StreamInfo));
    w.u16(m.width);
    w.u16(m.height);
    w.f32(m.fps);
    w.u8(uint8_t(m.mode));
    write_name(w, m.scene);
    return w.size();
}
std::size_t encode(const PoseMessage& m, std::span<uint8_t> out) {
    Writer w(out);
    w.u8(uint8_t(MessageType::Pose));
    w.u32(m.sequence);
    w.u64(uint64_t(m.client_time_us));
    w.f64(m.scene_time);
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) w.f32(m.view[c][r]);
    return w.size();
}
std::size_t encode(const AckMessage& m, std::span<uint8_t> out) {
    Writer w(out);
    w.u8(uint8_t(MessageType::Ack));
    w.u32(m.frame);
    return w.size();
}
std::size_t encode(const LossReportMessage& m, std::span<uint8_t> out) {
    REPRISE_ASSERT(m.count >= 1 && m.count <= kMaxLossReport);
    Writer w(out);
    w.u8(uint8_t(MessageType::LossReport));
    w.u8(m.count);
    for (int i = 0; i < m.count; ++i) w.u32(m.frames[i]);
    return w.size();
}
std::size_t encode(const ReceiverReportMessage& m, std::span<uint8_t> out) {
    Writer w(out);
    w.u8(uint8_t(MessageType::ReceiverReport));
    w.u32(m.received);
    w.u32(m.missing);
    w.u32(m.rtt_us);
    return w.size();
}
std::size_t encode(const FragmentMessage& m, std::span<uint8_t> out) {
    REPRISE_ASSERT(m.payload.size() <= kMaxFragmentPayload);
    Writer w(out);
    w.u8(uint8_t(MessageType::Fragment));
    w.u32(m.frame);
    w.u32(m.total_size);
    w.u16(m.index);
    w.u16(m.data_count);
    w.u16(m.fragment_size);
    w.u8(m.group_size);
    w.u8(uint8_t(m.kind));
    w.u64(uint64_t(m.pose_time_us));
    w.bytes(m.payload);
    return w.size();
}
std::size_t encode(const TicketMessage& m, std::span<uint8_t> out) {
    Writer w(out);
    w.u8(uint8_t(MessageType::Ticket));
    w.bytes(m.id);
    w.bytes(m.secret);
    return w.size();
}
std::size_t encode_empty(MessageType type, std::span<uint8_t> out) {
    Writer w(out);
    w.u8(uint8_t(type));
    return w.size();
}
std::size_t encode_error(const std::string& text, std::span<uint8_t> out) {
    Writer w(out);
    w.u8(uint8_t(MessageType::Error));
    const std::size_t n = std::min<std::size_t>(text.size(), 200);
    w.u8(uint8_t(n));
    w.bytes({reinterpret_cast<const uint8_t*>(text.data()), n});
    return w.size();
}

Status message_type(std::span<const uint8_t> plaintext, MessageType& type) {
    if (plaintext.empty()) return Status::error("message: empty");
    if (plaintext[0] < 1 || plaintext[0] > uint8_t(MessageType::Ticket))
        return Status::error("message: unknown type " + std::to_string(plaintext[0]));
    type = MessageType(plaintext[0]);
    return {};
}

Status parse(std::span<const uint8_t> plaintext, StartMessage& m) {
    Reader r(plaintext);
    REPRISE_TRY(expect(r, MessageType::Start, "start"));
    REPRISE_TRY(read_name(r, m.scene, true, "start"));
    return finish(r, "start");
}
Status parse(std::span<const uint8_t> plaintext, StreamInfoMessage& m) {
    Reader r(plaintext);
    REPRISE_TRY(expect(r, MessageType::StreamInfo, "stream info"));
    m.width = r.u16();
    m.height = r.u16();
    m.fps = r.f32();
    const uint8_t mode = r.u8();
    REPRISE_TRY(read_name(r, m.scene, false, "stream info"));
    REPRISE_TRY(finish(r, "stream info"));
    if (m.width < 1 || m.height < 1 || m.width > 8192 || m.height > 8192)
        return Status::error("stream info: size outside 1..8192");
    if (!(m.fps > 0.0f && m.fps <= 1000.0f))
        return Status::error("stream info: fps outside (0, 1000]");
    if (mode > 1) return Status::error("stream info: unknown mode " + std::to_string(mode));
    m.mode = StreamMode(mode);
    return {};
}
Status parse(std::span<const uint8_t> plaintext, PoseMessage& m) {
    Reader r(plaintext);
    REPRISE_TRY(expect(r, MessageType::Pose, "pose"));
    m.sequence = r.u32();
    m.client_time_us = int64_t(r.u64());
    m.scene_time = r.f64();
    for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row) m.view[c][row] = r.f32();
    REPRISE_TRY(finish(r, "pose"));
    if (!std::isfinite(m.scene_time) || std::abs(m.scene_time) > 1e9)
        return Status::error("pose: scene time not finite or beyond 1e9 s");
    for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row)
            if (!std::isfinite(m.view[c][row]) || std::abs(m.view[c][row]) > 1e7f)
                return Status::error("pose: view matrix entry not finite or beyond 1e7");
    return {};
}
Status parse(std::span<const uint8_t> plaintext, AckMessage& m) {
    Reader r(plaintext);
    REPRISE_TRY(expect(r, MessageType::Ack, "ack"));
    m.frame = r.u32();
    return finish(r, "ack");
}
Status parse(std::span<const uint8_t> plaintext, LossReportMessage& m) {
    Reader r(plaintext);
    REPRISE_TRY(expect(r, MessageType::LossReport, "loss report"));
    m.count = r.u8();
    if (m.count < 1 || m.count > kMaxLossReport)
        return Status::error("loss report: count outside 1..32");
    for (int i = 0; i < m.count; ++i) m.frames[i] = r.u32();
    return finish(r, "loss report");
}
Status parse(std::span<const uint8_t> plaintext, ReceiverReportMessage& m) {
    Reader r(plaintext);
    REPRISE_TRY(expect(r, MessageType::ReceiverReport, "receiver report"));
    m.received = r.u32();
    m.missing = r.u32();
    m.rtt_us = r.u32();
    return finish(r, "receiver report");
}
Status parse(std::span<const uint8_t> plaintext, FragmentMessage& m) {
    Reader r(plaintext);
    REPRISE_TRY(expect(r, MessageType::Fragment, "fragment"));
    m.frame = r.u32();
    m.total_size = r.u32();
    m.index = r.u16();
    m.data_count = r.u16();
    m.fragment_size = r.u16();
    m.group_size = r.u8();
    const uint8_t kind = r.u8();
    m.pose_time_us = int64_t(r.u64());
    if (!r.ok()) return Status::error("fragment: shorter than its 25-byte header");
    m.payload = r.bytes(r.remaining());
    if (kind > 1) return Status::error("fragment: unknown kind " + std::to_string(kind));
    m.kind = FragmentKind(kind);
    if (m.total_size == 0) return Status::error("fragment: packet size 0");
    if (m.data_count == 0) return Status::error("fragment: no data fragments");
    if (m.payload.empty()) return Status::error("fragment: empty payload");
    if (m.fragment_size == 0 || m.fragment_size > kMaxFragmentPayload)
        return Status::error("fragment: fragment size outside 1..1139");
    if (uint64_t(m.data_count - 1) * m.fragment_size >= m.total_size ||
        uint64_t(m.data_count) * m.fragment_size < m.total_size)
        return Status::error("fragment: count and fragment size disagree with the packet size");
    if (m.kind == FragmentKind::Data && m.index >= m.data_count)
        return Status::error("fragment: index " + std::to_string(m.index) + " beyond count " +
                             std::to_string(m.data_count));
    // Data fragment i holds bytes [i P, min((i + 1) P, total)); parity group j is as long as its
    // first data fragment, j g.
    std::size_t first = m.index;
    if (m.kind == FragmentKind::Parity) {
        if (m.group_size == 0) return Status::error("fragment: parity without a group size");
        const unsigned groups = (m.data_count + m.group_size - 1u) / m.group_size;
        if (m.index >= groups) return Status::error("fragment: parity group beyond the packet");
        first = std::size_t(m.index) * m.group_size;
    }
    const std::size_t expected =
        std::min<std::size_t>(m.fragment_size, m.total_size - first * m.fragment_size);
    if (m.payload.size() != expected)
        return Status::error("fragment: payload size disagrees with the header");
    return {};
}
Status parse(std::span<const uint8_t> plaintext, TicketMessage& m) {
    Reader r(plaintext);
    REPRISE_TRY(expect(r, MessageType::Ticket, "ticket"));
    auto id = r.bytes(kTicketIdSize), secret = r.bytes(kTicketSecretSize);
    REPRISE_TRY(finish(r, "ticket"));
    std::copy(id.begin(), id.end(), m.id.begin());
    std::copy(secret.begin(), secret.end(), m.secret.begin());
    return {};
}
Status parse_error(std::span<const uint8_t> plaintext, std::string& text) {
    Reader r(plaintext);
    REPRISE_TRY(expect(r, MessageType::Error, "error"));
    const std::size_t n = r.u8();
    auto b = r.bytes(n);
    REPRISE_TRY(finish(r, "error"));
    text.clear();
    for (uint8_t c : b) text.push_back(c >= 32 && c < 127 ? char(c) : '?');
    return {};
}

}  // namespace reprise::net
