#pragma once
// What travels on the wire: datagram header, the messages inside sealed datagrams, and the
// little-endian reader/writer that checks every length. Every field: docs/protocol.md.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>

#include <glm/mat4x4.hpp>

#include "reprise/core/byte_io.hpp"
#include "reprise/core/status.hpp"

namespace reprise::net {

constexpr uint8_t kMagic0 = 'R', kMagic1 = 'P';
constexpr uint8_t kProtocolVersion = 2;
constexpr std::size_t kMaxDatagram = 1200;
constexpr std::size_t kHeaderSize = 12;        // magic, version, type, connection id
constexpr std::size_t kSealedHeaderSize = 20;  // + u64 sequence number
constexpr std::size_t kAeadTagSize = 16;
constexpr std::size_t kMaxPlaintext = kMaxDatagram - kSealedHeaderSize - kAeadTagSize;  // 1164
constexpr std::size_t kMaxSceneName = 32;

enum class DatagramType : uint8_t {
    ClientHello = 1,
    ServerHello = 2,
    ClientFinish = 3,
    Sealed = 4,
    Refused = 5  // server -> client, unauthenticated: why a handshake was not admitted
};

struct DatagramHeader {
    DatagramType type = DatagramType::Sealed;
    uint64_t connection = 0;
};

// Messages inside a sealed datagram: one per datagram, the first plaintext byte is the type.
enum class MessageType : uint8_t {
    Start = 1,            // client -> server: scene name from the catalogue
    StreamInfo = 2,       // server -> client: size, rate, mode, scene (also a keep-alive)
    Pose = 3,             // client -> server
    Ack = 4,              // client -> server: frame decoded
    LossReport = 5,       // client -> server: frames that will never be decoded
    KeyFrameRequest = 6,  // client -> server
    ReceiverReport = 7,   // client -> server: media datagrams received / missing, cumulative
    Fragment = 8,         // server -> client: a piece (or FEC parity) of one codec packet
    Bye = 9,              // either side: the session ends
    Error = 10,           // server -> client: why a Start was refused (text)
    Ticket = 11,          // server -> client: resumption ticket for the next handshake
};

enum class StreamMode : uint8_t { Full = 0, LowRes = 1 };

struct StartMessage {
    std::string scene;  // [a-z0-9_-], 1..32 characters; empty: the server's default
};
struct StreamInfoMessage {
    uint16_t width = 0, height = 0;
    float fps = 0.0f;
    StreamMode mode = StreamMode::Full;
    std::string scene;
};
struct PoseMessage {
    uint32_t sequence = 0;
    int64_t client_time_us = 0;  // the client's clock when the pose was sampled
    double scene_time = 0.0;     // seconds on the scene's animation timeline
    glm::mat4 view{1.0f};        // world -> camera
};
struct AckMessage {
    uint32_t frame = 0;
};
constexpr std::size_t kMaxLossReport = 32;
struct LossReportMessage {
    uint8_t count = 0;
    std::array<uint32_t, kMaxLossReport> frames{};
};
struct ReceiverReportMessage {
    uint32_t received = 0;  // media datagrams received since the session started
    uint32_t missing =
        0;                // newest media sequence heard minus received: falls when a late one comes
    uint32_t rtt_us = 0;  // newest measured pose round trip (pose sampled -> frame decoded)
};
constexpr std::size_t kTicketIdSize = 16, kTicketSecretSize = 32;
struct TicketMessage {
    std::array<uint8_t, kTicketIdSize> id{};
    std::array<uint8_t, kTicketSecretSize> secret{};
};
enum class FragmentKind : uint8_t { Data = 0, Parity = 1 };
constexpr std::size_t kFragmentHeaderSize = 1 + 4 + 4 + 2 + 2 + 2 + 1 + 1 + 8;    // 25
constexpr std::size_t kMaxFragmentPayload = kMaxPlaintext - kFragmentHeaderSize;  // 1141
struct FragmentMessage {
    uint32_t frame = 0;          // codec frame number
    uint32_t total_size = 0;     // bytes of the whole codec packet
    uint16_t index = 0;          // data: fragment index; parity: group index
    uint16_t data_count = 0;     // data fragments of the packet
    uint16_t fragment_size = 0;  // payload bytes of every data fragment but the last, and of parity
    uint8_t group_size = 0;      // data fragments per parity group (0: no parity)
    FragmentKind kind = FragmentKind::Data;
    int64_t pose_time_us = 0;  // echo of the pose this frame was rendered from
    std::span<const uint8_t> payload;
};

// Refused (type 5): header, u8 reason, u8 sessions; 14 bytes, smaller than the hello or finish it
// answers (no amplification).
enum class RefusalReason : uint8_t { ServerFull = 1 };
constexpr std::size_t kRefusedSize = kHeaderSize + 2;
struct RefusedDatagram {
    uint64_t connection = 0;
    RefusalReason reason = RefusalReason::ServerFull;
    uint8_t sessions = 0;  // ServerFull: the server's session limit
};

// Little-endian writer into a fixed buffer (overflow is a contract violation of the caller) and
// the reader that checks every length (core/byte_io.hpp).
using Writer = FixedByteWriter;
using Reader = ByteReader;

void write_header(Writer& w, const DatagramHeader& header);
Status parse_header(std::span<const uint8_t> datagram, DatagramHeader& header);

std::size_t encode(const RefusedDatagram& d, std::span<uint8_t> out);
Status parse(std::span<const uint8_t> datagram, RefusedDatagram& d);

// Scene names: 1..32 of [a-z0-9_-] (never a path).
bool valid_scene_name(const std::string& name);

// Each encoder writes one message (type byte first) and returns its size (<= kMaxPlaintext).
std::size_t encode(const StartMessage& m, std::span<uint8_t> out);
std::size_t encode(const StreamInfoMessage& m, std::span<uint8_t> out);
std::size_t encode(const PoseMessage& m, std::span<uint8_t> out);
std::size_t encode(const AckMessage& m, std::span<uint8_t> out);
std::size_t encode(const LossReportMessage& m, std::span<uint8_t> out);
std::size_t encode(const ReceiverReportMessage& m, std::span<uint8_t> out);
std::size_t encode(const FragmentMessage& m, std::span<uint8_t> out);
std::size_t encode(const TicketMessage& m, std::span<uint8_t> out);
std::size_t encode_empty(MessageType type, std::span<uint8_t> out);  // KeyFrameRequest, Bye
std::size_t encode_error(const std::string& text, std::span<uint8_t> out);

// Parsers take the whole plaintext (type byte included) and check every field.
Status message_type(std::span<const uint8_t> plaintext, MessageType& type);
Status parse(std::span<const uint8_t> plaintext, StartMessage& m);
Status parse(std::span<const uint8_t> plaintext, StreamInfoMessage& m);
Status parse(std::span<const uint8_t> plaintext, PoseMessage& m);
Status parse(std::span<const uint8_t> plaintext, AckMessage& m);
Status parse(std::span<const uint8_t> plaintext, LossReportMessage& m);
Status parse(std::span<const uint8_t> plaintext, ReceiverReportMessage& m);
Status parse(std::span<const uint8_t> plaintext, FragmentMessage& m);
Status parse(std::span<const uint8_t> plaintext, TicketMessage& m);
Status parse_error(std::span<const uint8_t> plaintext, std::string& text);

}  // namespace reprise::net
