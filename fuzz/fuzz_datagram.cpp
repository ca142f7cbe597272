// libFuzzer target: everything a datagram from the network reaches before and after
// authentication — header, handshake messages, the sealed channel, every message parser and
// the fragment reassembler (fed a sequence of fragments split out of the input).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "reprise/net/fragment.hpp"
#include "reprise/net/secure.hpp"
#include "reprise/net/wire.hpp"

using namespace reprise::net;

namespace {

void parse_all(std::span<const uint8_t> m) {
    MessageType type;
    if (!message_type(m, type).ok()) return;
    StartMessage start;
    StreamInfoMessage info;
    PoseMessage pose;
    AckMessage ack;
    LossReportMessage loss;
    ReceiverReportMessage report;
    FragmentMessage fragment;
    TicketMessage ticket;
    std::string text;
    (void)parse(m, start);
    (void)parse(m, info);
    (void)parse(m, pose);
    (void)parse(m, ack);
    (void)parse(m, loss);
    (void)parse(m, report);
    (void)parse(m, fragment);
    (void)parse(m, ticket);
    (void)parse_error(m, text);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
    static const bool ready = init_crypto().ok();
    if (!ready) return 0;
    const std::span<const uint8_t> input(data, size);

    DatagramHeader header;
    (void)parse_header(input, header);
    std::vector<uint8_t> reply;
    PendingHandshake pending;
    bool has_ticket = false;
    std::array<uint8_t, kTicketIdSize> ticket_id{};
    (void)client_hello_ticket(input, has_ticket, ticket_id);
    if (answer_client_hello("1234", input, reply, pending).ok())
        (void)check_client_finish(pending, input);
    ClientHandshake client;
    std::vector<uint8_t> hello, finish;
    client.start("1234", hello);
    SessionKeys keys;
    (void)client.finish(input, finish, keys);

    // Fixed keys: the fuzzer cannot forge the tag, so the plaintext parsers are fuzzed directly.
    Key k{};
    SecureChannel channel(header.connection, k, k);
    std::vector<uint8_t> plain;
    (void)channel.open(input, plain);
    parse_all(input);

    // A sequence of fragments: each chunk starts with a one-byte length.
    Reassembler reassembler({.slots = 3, .max_packet_bytes = 1 << 16});
    std::vector<uint32_t> abandoned;
    Reassembled out;
    std::size_t pos = 0;
    while (pos < size) {
        const std::size_t n = std::min<std::size_t>(data[pos], size - pos - 1);
        const std::span<const uint8_t> chunk(data + pos + 1, n);
        pos += 1 + n;
        FragmentMessage f;
        if (!parse(chunk, f).ok()) continue;
        if (reassembler.add(f, out, abandoned) && out.data.size() != f.total_size) __builtin_trap();
        if (abandoned.size() > 1024) abandoned.clear();
    }
    return 0;
}
