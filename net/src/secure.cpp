#include "reprise/net/secure.hpp"

#include <sodium.h>

#include <algorithm>

namespace reprise::net {

namespace {

// ClientHello padding: u8 kind (0 PIN, 1 resumption), then the ticket id; zeros after.
constexpr std::size_t kHelloPaddingAt = kHeaderSize + 32 + 32;  // 76
constexpr uint8_t kHelloResumes = 1;

constexpr char kKdfContext[crypto_kdf_CONTEXTBYTES + 1] = "reprise1";
enum Subkey : uint64_t {
    ClientToServer = 1,
    ServerToClient = 2,
    ServerConfirm = 3,
    ClientConfirm = 4
};

// CPace generator: a ristretto255 point from the secret, the client's nonce and the connection.
Status generator(const std::string& secret, std::span<const uint8_t, 32> client_nonce,
                 uint64_t connection, std::array<uint8_t, 32>& g) {
    if (secret.empty() || secret.size() > 255)
        return Status::error("handshake: secret must be 1..255 bytes");
    uint8_t hash[crypto_core_ristretto255_HASHBYTES];
    crypto_generichash_state st;
    crypto_generichash_init(&st, nullptr, 0, sizeof hash);
    static const char label[] = "reprise cpace generator v1";
    crypto_generichash_update(&st, reinterpret_cast<const uint8_t*>(label), sizeof label - 1);
    const uint8_t len = uint8_t(secret.size());
    crypto_generichash_update(&st, &len, 1);
    crypto_generichash_update(&st, reinterpret_cast<const uint8_t*>(secret.data()), secret.size());
    crypto_generichash_update(&st, client_nonce.data(), 32);
    uint8_t conn[8];
    for (int i = 0; i < 8; ++i) conn[i] = uint8_t(connection >> (8 * i));
    crypto_generichash_update(&st, conn, 8);
    crypto_generichash_final(&st, hash, sizeof hash);
    crypto_core_ristretto255_from_hash(g.data(), hash);
    sodium_memzero(hash, sizeof hash);
    return {};
}

struct Derived {
    SessionKeys keys;
    Key server_tag{}, client_tag{};
};

// Keys and both confirmation tags from the shared point and the whole transcript.
void derive(const uint8_t shared[32], uint64_t connection, const uint8_t* client_nonce,
            const uint8_t* server_nonce, const uint8_t* client_share, const uint8_t* server_share,
            Derived& d) {
    uint8_t master[32];
    crypto_generichash_state st;
    crypto_generichash_init(&st, shared, 32, sizeof master);
    static const char label[] = "reprise session v1";
    crypto_generichash_update(&st, reinterpret_cast<const uint8_t*>(label), sizeof label - 1);
    uint8_t conn[8];
    for (int i = 0; i < 8; ++i) conn[i] = uint8_t(connection >> (8 * i));
    crypto_generichash_update(&st, conn, 8);
    crypto_generichash_update(&st, client_nonce, 32);
    crypto_generichash_update(&st, server_nonce, 32);
    crypto_generichash_update(&st, client_share, 32);
    crypto_generichash_update(&st, server_share, 32);
    crypto_generichash_final(&st, master, sizeof master);
    Key confirm_s, confirm_c;
    crypto_kdf_derive_from_key(d.keys.client_to_server.data(), 32, ClientToServer, kKdfContext,
                               master);
    crypto_kdf_derive_from_key(d.keys.server_to_client.data(), 32, ServerToClient, kKdfContext,
                               master);
    crypto_kdf_derive_from_key(confirm_s.data(), 32, ServerConfirm, kKdfContext, master);
    crypto_kdf_derive_from_key(confirm_c.data(), 32, ClientConfirm, kKdfContext, master);
    auto tag = [&](const Key& key, const char* who, Key& out) {
        crypto_generichash_state t;
        crypto_generichash_init(&t, key.data(), key.size(), out.size());
        crypto_generichash_update(&t, reinterpret_cast<const uint8_t*>(who), 6);
        crypto_generichash_update(&t, client_share, 32);
        crypto_generichash_update(&t, server_share, 32);
        crypto_generichash_final(&t, out.data(), out.size());
    };
    tag(confirm_s, "server", d.server_tag);
    tag(confirm_c, "client", d.client_tag);
    sodium_memzero(master, sizeof master);
    sodium_memzero(confirm_s.data(), 32);
    sodium_memzero(confirm_c.data(), 32);
}

}  // namespace

Status init_crypto() {
    if (sodium_init() < 0) return Status::error("libsodium: initialisation failed");
    return {};
}

uint64_t random_u64() {
    uint64_t v = 0;
    while (v == 0) randombytes_buf(&v, sizeof v);
    return v;
}

void random_bytes(std::span<uint8_t> out) { randombytes_buf(out.data(), out.size()); }

ClientHandshake::~ClientHandshake() { sodium_memzero(scalar_.data(), scalar_.size()); }

void ClientHandshake::start(const std::string& secret, std::vector<uint8_t>& hello,
                            const ResumptionTicket* ticket) {
    connection_ = random_u64();
    randombytes_buf(nonce_.data(), nonce_.size());
    const bool resume = ticket && ticket->valid;
    REPRISE_ASSERT(
        generator(resume ? ticket->secret_text() : secret, nonce_, connection_, generator_).ok());
    do {
        crypto_core_ristretto255_scalar_random(scalar_.data());
    } while (crypto_scalarmult_ristretto255(share_.data(), scalar_.data(), generator_.data()) != 0);
    hello.assign(kClientHelloSize, 0);
    Writer w(hello);
    write_header(w, {.type = DatagramType::ClientHello, .connection = connection_});
    w.bytes(nonce_);
    w.bytes(share_);
    if (resume) {
        w.u8(kHelloResumes);
        w.bytes(ticket->id);
    }
}

Status client_hello_ticket(std::span<const uint8_t> client_hello, bool& has_ticket,
                           std::array<uint8_t, kTicketIdSize>& id) {
    if (client_hello.size() != kClientHelloSize) return Status::error("client hello: wrong size");
    Reader r(client_hello.subspan(kHelloPaddingAt));
    const uint8_t kind = r.u8();
    auto ticket = r.bytes(kTicketIdSize);
    if (kind > kHelloResumes) return Status::error("client hello: unknown kind");
    has_ticket = kind == kHelloResumes;
    if (has_ticket) std::copy(ticket.begin(), ticket.end(), id.begin());
    for (std::size_t i = has_ticket ? kHelloPaddingAt + 1 + kTicketIdSize : kHelloPaddingAt;
         i < client_hello.size(); ++i)
        if (client_hello[i] != 0) return Status::error("client hello: padding is not zero");
    return {};
}

Status ClientHandshake::finish(std::span<const uint8_t> server_hello,
                               std::vector<uint8_t>& client_finish, SessionKeys& keys) {
    DatagramHeader h;
    REPRISE_TRY(parse_header(server_hello, h));
    if (h.type != DatagramType::ServerHello || server_hello.size() != kServerHelloSize)
        return Status::error("server hello: wrong type or size");
    if (h.connection != connection_) return Status::error("server hello: another connection");
    Reader r(server_hello.subspan(kHeaderSize));
    auto server_nonce = r.bytes(32), server_share = r.bytes(32), tag = r.bytes(32);
    uint8_t shared[32];
    if (crypto_scalarmult_ristretto255(shared, scalar_.data(), server_share.data()) != 0)
        return Status::error("server hello: invalid share");
    Derived d;
    derive(shared, connection_, nonce_.data(), server_nonce.data(), share_.data(),
           server_share.data(), d);
    sodium_memzero(shared, sizeof shared);
    if (sodium_memcmp(d.server_tag.data(), tag.data(), 32) != 0)
        return Status::error("server hello: key confirmation failed (wrong PIN?)");
    client_finish.assign(kClientFinishSize, 0);
    Writer w(client_finish);
    write_header(w, {.type = DatagramType::ClientFinish, .connection = connection_});
    w.bytes(d.client_tag);
    keys = d.keys;
    return {};
}

Status answer_client_hello(const std::string& secret, std::span<const uint8_t> client_hello,
                           std::vector<uint8_t>& server_hello, PendingHandshake& pending) {
    DatagramHeader h;
    REPRISE_TRY(parse_header(client_hello, h));
    if (h.type != DatagramType::ClientHello || client_hello.size() != kClientHelloSize)
        return Status::error("client hello: wrong type or size");
    Reader r(client_hello.subspan(kHeaderSize));
    auto nonce = r.bytes(32), client_share = r.bytes(32);
    if (crypto_core_ristretto255_is_valid_point(client_share.data()) != 1)
        return Status::error("client hello: share is not a valid point");
    std::array<uint8_t, 32> g, scalar, share, server_nonce;
    REPRISE_TRY(generator(secret, std::span<const uint8_t, 32>(nonce.data(), 32), h.connection, g));
    do {
        crypto_core_ristretto255_scalar_random(scalar.data());
    } while (crypto_scalarmult_ristretto255(share.data(), scalar.data(), g.data()) != 0);
    uint8_t shared[32];
    const bool bad =
        crypto_scalarmult_ristretto255(shared, scalar.data(), client_share.data()) != 0;
    sodium_memzero(scalar.data(), 32);
    if (bad) return Status::error("client hello: share gives the identity");
    randombytes_buf(server_nonce.data(), 32);
    Derived d;
    derive(shared, h.connection, nonce.data(), server_nonce.data(), client_share.data(),
           share.data(), d);
    sodium_memzero(shared, sizeof shared);
    server_hello.assign(kServerHelloSize, 0);
    Writer w(server_hello);
    write_header(w, {.type = DatagramType::ServerHello, .connection = h.connection});
    w.bytes(server_nonce);
    w.bytes(share);
    w.bytes(d.server_tag);
    pending.connection = h.connection;
    pending.client_confirm = d.client_tag;
    pending.keys = d.keys;
    return {};
}

Status check_client_finish(const PendingHandshake& pending,
                           std::span<const uint8_t> client_finish) {
    DatagramHeader h;
    REPRISE_TRY(parse_header(client_finish, h));
    if (h.type != DatagramType::ClientFinish || client_finish.size() != kClientFinishSize)
        return Status::error("client finish: wrong type or size");
    if (h.connection != pending.connection)
        return Status::error("client finish: another connection");
    if (sodium_memcmp(client_finish.data() + kHeaderSize, pending.client_confirm.data(), 32) != 0)
        return Status::error("client finish: key confirmation failed (wrong PIN?)");
    return {};
}

bool ReplayWindow::seen_or_too_old(uint64_t seq) const {
    if (seq == 0) return true;
    if (seq > newest_) return false;
    const uint64_t age = newest_ - seq;
    if (age >= kSize) return true;
    return (bits_[(seq % kSize) / 64] >> (seq % 64)) & 1u;
}

void ReplayWindow::mark(uint64_t seq) {
    if (seq > newest_) {
        const uint64_t advance = seq - newest_;
        if (advance >= kSize) {
            bits_.fill(0);
        } else {
            for (uint64_t s = newest_ + 1; s <= seq; ++s)
                bits_[(s % kSize) / 64] &= ~(uint64_t(1) << (s % 64));
        }
        newest_ = seq;
    }
    bits_[(seq % kSize) / 64] |= uint64_t(1) << (seq % 64);
}

SecureChannel::SecureChannel(uint64_t connection, const Key& send_key, const Key& receive_key)
    : connection_(connection), send_key_(send_key), receive_key_(receive_key) {}

SecureChannel::~SecureChannel() {
    sodium_memzero(send_key_.data(), 32);
    sodium_memzero(receive_key_.data(), 32);
}

namespace {
void nonce_of(uint64_t seq, uint8_t nonce[12]) {
    for (int i = 0; i < 4; ++i) nonce[i] = 0;
    for (int i = 0; i < 8; ++i) nonce[4 + i] = uint8_t(seq >> (8 * i));
}
}  // namespace

void SecureChannel::seal(std::span<const uint8_t> plaintext, std::vector<uint8_t>& datagram) {
    REPRISE_ASSERT(plaintext.size() <= kMaxPlaintext);
    const uint64_t seq = next_send_++;
    datagram.resize(kSealedHeaderSize + plaintext.size() + kAeadTagSize);
    Writer w(datagram);
    write_header(w, {.type = DatagramType::Sealed, .connection = connection_});
    w.u64(seq);
    uint8_t nonce[12];
    nonce_of(seq, nonce);
    unsigned long long written = 0;
    crypto_aead_chacha20poly1305_ietf_encrypt(datagram.data() + kSealedHeaderSize, &written,
                                              plaintext.data(), plaintext.size(), datagram.data(),
                                              kSealedHeaderSize, nullptr, nonce, send_key_.data());
    REPRISE_ASSERT(written == plaintext.size() + kAeadTagSize);
}

Status SecureChannel::open(std::span<const uint8_t> datagram, std::vector<uint8_t>& plaintext) {
    DatagramHeader h;
    REPRISE_TRY(parse_header(datagram, h));
    if (h.type != DatagramType::Sealed) return Status::error("sealed datagram: wrong type");
    if (h.connection != connection_) return Status::error("sealed datagram: another connection");
    if (datagram.size() < kSealedHeaderSize + kAeadTagSize)
        return Status::error("sealed datagram: shorter than header and tag");
    Reader r(datagram.subspan(kHeaderSize, 8));
    const uint64_t seq = r.u64();
    if (window_.seen_or_too_old(seq)) return Status::error("sealed datagram: replayed or too old");
    uint8_t nonce[12];
    nonce_of(seq, nonce);
    plaintext.resize(datagram.size() - kSealedHeaderSize - kAeadTagSize);
    unsigned long long length = 0;
    if (crypto_aead_chacha20poly1305_ietf_decrypt(
            plaintext.data(), &length, nullptr, datagram.data() + kSealedHeaderSize,
            datagram.size() - kSealedHeaderSize, datagram.data(), kSealedHeaderSize, nonce,
            receive_key_.data()) != 0) {
        plaintext.clear();
        return Status::error("sealed datagram: authentication failed");
    }
    plaintext.resize(length);
    window_.mark(seq);
    return {};
}

}  // namespace reprise::net
