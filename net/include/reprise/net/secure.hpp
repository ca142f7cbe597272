#pragma once
// Authentication and encryption (libsodium). The handshake is CPace on ristretto255: both sides
// derive the group generator from the PIN (or token) and the client's nonce, exchange ephemeral
// Diffie-Hellman shares on it and confirm the resulting keys both ways. The PIN never travels;
// a passive observer learns nothing to test PIN guesses against, and an active attacker tests
// exactly one guess per handshake (which the server rate limits). Then every datagram is
// ChaCha20-Poly1305 (IETF) with a 64-bit sequence number as nonce and a replay window.
// Threat model: docs/protocol.md.
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "reprise/core/status.hpp"
#include "reprise/net/wire.hpp"

namespace reprise::net {

using Key = std::array<uint8_t, 32>;

constexpr std::size_t kClientHelloSize = 128;  // padded: the reply is never larger than the request
constexpr std::size_t kServerHelloSize = kHeaderSize + 32 + 32 + 32;  // 108
constexpr std::size_t kClientFinishSize = kHeaderSize + 32;           // 44

// libsodium must be initialised once before any of this; safe to call many times.
Status init_crypto();
uint64_t random_u64();
void random_bytes(std::span<uint8_t> out);

struct SessionKeys {
    Key client_to_server{};
    Key server_to_client{};
};

// A resumption ticket (docs/protocol.md, "Resumption"): the server's id for a secret it sent
// inside an earlier session; a hello naming it runs CPace on the secret instead of the PIN.
struct ResumptionTicket {
    std::array<uint8_t, kTicketIdSize> id{};
    std::array<uint8_t, kTicketSecretSize> secret{};
    bool valid = false;
    std::string secret_text() const { return {secret.begin(), secret.end()}; }
};

// What a ClientHello's padding says: PIN (no ticket) or the ticket id it names. Refuses a hello
// of another size or with padding that is not zero.
Status client_hello_ticket(std::span<const uint8_t> client_hello, bool& has_ticket,
                           std::array<uint8_t, kTicketIdSize>& id);

// Client side of the handshake.
class ClientHandshake {
public:
    // Builds the ClientHello (kClientHelloSize bytes) for a new random connection id; with a
    // ticket, the ticket's secret replaces `secret` and its id goes into the padding.
    void start(const std::string& secret, std::vector<uint8_t>& hello,
               const ResumptionTicket* ticket = nullptr);
    // Checks the ServerHello's key confirmation; on success writes the ClientFinish and the keys.
    Status finish(std::span<const uint8_t> server_hello, std::vector<uint8_t>& client_finish,
                  SessionKeys& keys);
    uint64_t connection() const { return connection_; }
    ~ClientHandshake();

private:
    uint64_t connection_ = 0;
    std::array<uint8_t, 32> nonce_{}, share_{}, scalar_{}, generator_{};
};

// Server side: answers one ClientHello; what it must remember until the ClientFinish arrives.
struct PendingHandshake {
    uint64_t connection = 0;
    Key client_confirm{};  // the tag the client must send
    SessionKeys keys;
};
Status answer_client_hello(const std::string& secret, std::span<const uint8_t> client_hello,
                           std::vector<uint8_t>& server_hello, PendingHandshake& pending);
// True when `client_finish` carries the expected confirmation (constant-time compare).
Status check_client_finish(const PendingHandshake& pending, std::span<const uint8_t> client_finish);

// Sliding window over the newest 256 sequence numbers.
class ReplayWindow {
public:
    bool seen_or_too_old(uint64_t seq) const;
    void mark(uint64_t seq);
    uint64_t newest() const { return newest_; }

private:
    static constexpr uint64_t kSize = 256;
    uint64_t newest_ = 0;  // 0: nothing yet (sequence numbers start at 1)
    std::array<uint64_t, kSize / 64> bits_{};
};

// One direction pair of an authenticated session.
class SecureChannel {
public:
    SecureChannel() = default;
    SecureChannel(uint64_t connection, const Key& send_key, const Key& receive_key);
    ~SecureChannel();
    SecureChannel(const SecureChannel&) = default;
    SecureChannel& operator=(const SecureChannel&) = default;

    // Seals `plaintext` (<= kMaxPlaintext) into `datagram` (resized; <= 1200 bytes).
    void seal(std::span<const uint8_t> plaintext, std::vector<uint8_t>& datagram);
    // Opens a sealed datagram: header, connection, replay window, then AEAD; only then is the
    // sequence number marked seen. `plaintext` is resized to what it holds.
    Status open(std::span<const uint8_t> datagram, std::vector<uint8_t>& plaintext);

    uint64_t connection() const { return connection_; }
    uint64_t sent() const { return next_send_ - 1; }
    uint64_t newest_received() const { return window_.newest(); }

private:
    uint64_t connection_ = 0;
    Key send_key_{}, receive_key_{};
    uint64_t next_send_ = 1;
    ReplayWindow window_;
};

}  // namespace reprise::net
