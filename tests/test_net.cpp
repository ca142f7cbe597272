// net/: wire format, handshake, sealed channel, fragmentation + FEC, fault injector, rate limit.
#include <gtest/gtest.h>

#include <random>

#include "reprise/net/fault_injector.hpp"
#include "reprise/net/fragment.hpp"
#include "reprise/net/guess_budget.hpp"
#include "reprise/net/rate_limiter.hpp"
#include "reprise/net/secure.hpp"
#include "reprise/net/udp.hpp"
#include "reprise/net/wire.hpp"

using namespace reprise;
using namespace reprise::net;

namespace {

struct Keys {
    SessionKeys client, server;
    uint64_t connection = 0;
};

// A whole handshake in memory; false when either side refused.
bool handshake(const std::string& client_secret, const std::string& server_secret, Keys& keys) {
    ClientHandshake client;
    std::vector<uint8_t> hello, server_hello, finish;
    client.start(client_secret, hello);
    EXPECT_EQ(hello.size(), kClientHelloSize);
    PendingHandshake pending;
    if (!answer_client_hello(server_secret, hello, server_hello, pending).ok()) return false;
    EXPECT_LE(server_hello.size(), hello.size());  // no amplification
    if (!client.finish(server_hello, finish, keys.client).ok()) return false;
    if (!check_client_finish(pending, finish).ok()) return false;
    keys.server = pending.keys;
    keys.connection = client.connection();
    return true;
}

}  // namespace

TEST(NetHandshake, SamePinGivesTheSameKeysBothWays) {
    ASSERT_TRUE(init_crypto().ok());
    Keys k;
    ASSERT_TRUE(handshake("4711", "4711", k));
    EXPECT_EQ(k.client.client_to_server, k.server.client_to_server);
    EXPECT_EQ(k.client.server_to_client, k.server.server_to_client);
    EXPECT_NE(k.client.client_to_server, k.client.server_to_client);
    Keys again;
    ASSERT_TRUE(handshake("4711", "4711", again));
    EXPECT_NE(k.client.client_to_server, again.client.client_to_server);  // ephemeral
}

TEST(NetHandshake, WrongPinFailsKeyConfirmationOnBothSides) {
    ASSERT_TRUE(init_crypto().ok());
    ClientHandshake client;
    std::vector<uint8_t> hello, server_hello, finish;
    client.start("1234", hello);
    PendingHandshake pending;
    ASSERT_TRUE(answer_client_hello("9999", hello, server_hello, pending).ok());
    SessionKeys keys;
    EXPECT_FALSE(client.finish(server_hello, finish, keys).ok());
    // A forged finish (the client never made one) fails the server's check too.
    std::vector<uint8_t> forged(kClientFinishSize, 0);
    Writer w(forged);
    write_header(w, {.type = DatagramType::ClientFinish, .connection = pending.connection});
    EXPECT_FALSE(check_client_finish(pending, forged).ok());
    // The PIN appears nowhere in what was sent.
    const std::string pin = "1234";
    for (const auto* d : {&hello, &server_hello})
        EXPECT_EQ(std::search(d->begin(), d->end(), pin.begin(), pin.end()), d->end());
}

TEST(NetHandshake, MalformedHellosAreRefused) {
    ASSERT_TRUE(init_crypto().ok());
    ClientHandshake client;
    std::vector<uint8_t> hello, reply;
    client.start("1234", hello);
    PendingHandshake pending;
    std::vector<uint8_t> truncated(hello.begin(), hello.end() - 1);
    EXPECT_FALSE(answer_client_hello("1234", truncated, reply, pending).ok());
    std::vector<uint8_t> bad_point = hello;
    for (int i = 0; i < 32; ++i)
        bad_point[kHeaderSize + 32 + i] = 0xff;  // not a canonical encoding
    EXPECT_FALSE(answer_client_hello("1234", bad_point, reply, pending).ok());
    std::vector<uint8_t> identity = hello;
    std::fill(identity.begin() + kHeaderSize + 32, identity.begin() + kHeaderSize + 64, 0);
    EXPECT_FALSE(answer_client_hello("1234", identity, reply, pending).ok());
}

TEST(NetChannel, SealOpenRejectsReplayTamperAndOtherKeys) {
    ASSERT_TRUE(init_crypto().ok());
    Keys k;
    ASSERT_TRUE(handshake("pin", "pin", k));
    SecureChannel client(k.connection, k.client.client_to_server, k.client.server_to_client);
    SecureChannel server(k.connection, k.server.server_to_client, k.server.client_to_server);
    std::vector<uint8_t> message(100), datagram, plain;
    for (std::size_t i = 0; i < message.size(); ++i) message[i] = uint8_t(i);
    client.seal(message, datagram);
    ASSERT_LE(datagram.size(), kMaxDatagram);
    ASSERT_TRUE(server.open(datagram, plain).ok());
    EXPECT_EQ(plain, message);
    EXPECT_FALSE(server.open(datagram, plain).ok()) << "replay accepted";
    client.seal(message, datagram);
    std::vector<uint8_t> tampered = datagram;
    tampered[kSealedHeaderSize + 3] ^= 1;
    EXPECT_FALSE(server.open(tampered, plain).ok());
    tampered = datagram;
    tampered[13] ^= 1;  // the sequence number is authenticated too
    EXPECT_FALSE(server.open(tampered, plain).ok());
    EXPECT_TRUE(server.open(datagram, plain).ok())
        << "a rejected forgery must not burn the sequence number";
    // The server's own direction does not open as the client's.
    server.seal(message, datagram);
    EXPECT_FALSE(server.open(datagram, plain).ok());
    EXPECT_TRUE(client.open(datagram, plain).ok());
}

TEST(NetChannel, ReplayWindowAcceptsReorderingRejectsDuplicatesAndOld) {
    ReplayWindow w;
    EXPECT_TRUE(w.seen_or_too_old(0));
    for (uint64_t s : {5, 3, 4, 1, 2, 300}) {
        EXPECT_FALSE(w.seen_or_too_old(s)) << s;
        w.mark(s);
        EXPECT_TRUE(w.seen_or_too_old(s)) << s;
    }
    EXPECT_TRUE(w.seen_or_too_old(44));  // 256 or more behind the newest
    EXPECT_FALSE(w.seen_or_too_old(299));
    EXPECT_FALSE(w.seen_or_too_old(100));
}

TEST(NetWire, MessagesRoundTripAndTruncationsAreRefused) {
    std::vector<uint8_t> buf(kMaxPlaintext);
    PoseMessage pose{.sequence = 7, .client_time_us = -5, .scene_time = 1.25};
    pose.view[3][0] = 2.5f;
    buf.resize(encode(pose, buf));
    PoseMessage back;
    ASSERT_TRUE(parse(buf, back).ok());
    EXPECT_EQ(back.sequence, 7u);
    EXPECT_EQ(back.client_time_us, -5);
    EXPECT_EQ(back.view[3][0], 2.5f);
    for (std::size_t n = 0; n < buf.size(); ++n)
        EXPECT_FALSE(parse(std::span<const uint8_t>(buf.data(), n), back).ok()) << n;
    buf.push_back(0);
    EXPECT_FALSE(parse(buf, back).ok()) << "trailing byte";

    buf.assign(kMaxPlaintext, 0);
    buf.resize(encode(StartMessage{.scene = "fence"}, buf));
    StartMessage start;
    ASSERT_TRUE(parse(buf, start).ok());
    EXPECT_EQ(start.scene, "fence");
    EXPECT_FALSE(valid_scene_name("../etc/passwd"));
    EXPECT_FALSE(valid_scene_name("/tmp/x.glb"));
    EXPECT_FALSE(valid_scene_name(std::string(33, 'a')));
    std::vector<uint8_t> path = {uint8_t(MessageType::Start), 6, '.', '.', '/', 'x', '.', 'g'};
    EXPECT_FALSE(parse(path, start).ok());

    std::vector<uint8_t> nan_pose(kMaxPlaintext);
    pose.view[1][1] = std::numeric_limits<float>::quiet_NaN();
    nan_pose.resize(encode(pose, nan_pose));
    EXPECT_FALSE(parse(nan_pose, back).ok());
}

TEST(NetWire, HeadersOfEveryKindOfGarbageAreRefused) {
    DatagramHeader h;
    std::vector<uint8_t> d(kMaxDatagram + 1, 0);
    EXPECT_FALSE(parse_header(d, h).ok());  // oversized
    d.assign({'R', 'P', kProtocolVersion, 4});
    EXPECT_FALSE(parse_header(d, h).ok());  // truncated
    d.assign(20, 0);
    EXPECT_FALSE(parse_header(d, h).ok());  // bad magic
    d[0] = 'R', d[1] = 'P', d[2] = 1, d[3] = 4;
    EXPECT_FALSE(parse_header(d, h).ok());  // version 1 (full-length parity)
    d[2] = 3;
    EXPECT_FALSE(parse_header(d, h).ok());
    d[2] = 2, d[3] = 9;
    EXPECT_FALSE(parse_header(d, h).ok());  // type
    d[3] = 4;
    EXPECT_TRUE(parse_header(d, h).ok());
}

TEST(NetFragment, EveryPacketSizeReassemblesAndOneLossPerGroupIsRecovered) {
    std::mt19937 rng(3);
    for (std::size_t size : {1, 2, 100, 1099, 1100, 1101, 5000, 8800, 8801, 40000}) {
        std::vector<uint8_t> packet(size);
        for (auto& b : packet) b = uint8_t(rng());
        std::vector<std::vector<uint8_t>> messages;
        const std::size_t n =
            fragment_packet(packet, 9, 1234, {.group = 4, .fragment_payload = 1100}, messages);
        const std::size_t data = (size + 1099) / 1100;
        ASSERT_EQ(n, data + (data + 3) / 4);
        for (std::size_t i = 0; i < n; ++i) ASSERT_LE(messages[i].size(), kMaxPlaintext);
        // Parity is as long as its group's first fragment: a 100-byte packet costs 100 more.
        for (std::size_t j = 0; data + j < n; ++j) {
            FragmentMessage f;
            ASSERT_TRUE(parse(messages[data + j], f).ok());
            EXPECT_EQ(f.payload.size(), std::min<std::size_t>(1100, size - j * 4 * 1100)) << size;
        }
        for (int drop_mode = 0; drop_mode < 3; ++drop_mode) {
            Reassembler r;
            std::vector<uint32_t> abandoned;
            Reassembled out;
            bool done = false;
            for (std::size_t k = 0; k < n; ++k) {
                const std::size_t i = n - 1 - k;  // reversed: parity first
                // Drop mode 1: the first data fragment of each group; 2: the last data fragment.
                if (drop_mode == 1 && i < data && i % 4 == 0) continue;
                if (drop_mode == 2 && i == data - 1) continue;
                FragmentMessage f;
                ASSERT_TRUE(parse(messages[i], f).ok());
                done = r.add(f, out, abandoned) || done;
                if (done) break;
            }
            ASSERT_TRUE(done) << size << " mode " << drop_mode;
            EXPECT_EQ(out.frame, 9u);
            EXPECT_EQ(out.pose_time_us, 1234);
            EXPECT_TRUE(std::equal(out.data.begin(), out.data.end(), packet.begin(), packet.end()))
                << size;
        }
    }
}

TEST(NetFragment, ReassemblerMemoryStaysBoundedAndOldFramesAreGivenUp) {
    Reassembler r({.slots = 3, .max_packet_bytes = 20000});
    std::vector<uint8_t> packet(10000, 7);
    std::vector<std::vector<uint8_t>> messages;
    std::vector<uint32_t> abandoned;
    Reassembled out;
    for (uint32_t frame = 0; frame < 50; ++frame) {
        fragment_packet(packet, frame, 0, {.group = 0}, messages);
        FragmentMessage f;
        ASSERT_TRUE(parse(messages[0], f).ok());
        EXPECT_FALSE(r.add(f, out, abandoned));  // never complete
        EXPECT_LE(r.bytes_held(), std::size_t(3 * 12000));
    }
    EXPECT_EQ(abandoned.size(), 47u);
    std::vector<uint8_t> big(30000, 1);
    fragment_packet(big, 60, 0, {.group = 0}, messages);
    FragmentMessage f;
    ASSERT_TRUE(parse(messages[0], f).ok());
    EXPECT_FALSE(r.add(f, out, abandoned));
    EXPECT_EQ(r.stats().stale, 1u);  // larger than allowed: never buffered
}

TEST(NetFragment, InconsistentFragmentsAreRefused) {
    std::vector<uint8_t> buf(kMaxPlaintext);
    std::vector<uint8_t> payload(100, 1);
    FragmentMessage m{.frame = 1,
                      .total_size = 100,
                      .index = 0,
                      .data_count = 2,
                      .fragment_size = 100,
                      .payload = payload};
    buf.resize(encode(m, buf));
    FragmentMessage back;
    EXPECT_FALSE(parse(buf, back).ok());  // two fragments of 100 cannot make 100 bytes
}

TEST(NetFaults, SameSeedSameOutcomeAndLossRateNearTheSetting) {
    auto run = [](uint64_t seed, std::vector<int>& order, FaultStats& stats) {
        FaultInjector f(
            {.loss = 0.05, .burst_start = 0.01, .jitter_ms = 10, .reorder = 0.1, .seed = seed});
        std::vector<uint8_t> d(4), out;
        int64_t now = 0;
        for (int i = 0; i < 20000; ++i) {
            d[0] = uint8_t(i), d[1] = uint8_t(i >> 8), d[2] = uint8_t(i >> 16);
            f.submit(d, now);
            now += 1000;
            while (f.deliver(now, out)) order.push_back(out[0] | out[1] << 8 | out[2] << 16);
        }
        while (f.deliver(now + 1'000'000, out))
            order.push_back(out[0] | out[1] << 8 | out[2] << 16);
        stats = f.stats();
    };
    std::vector<int> a, b, c;
    FaultStats sa, sb, sc;
    run(1, a, sa);
    run(1, b, sb);
    run(2, c, sc);
    EXPECT_EQ(a, b);
    EXPECT_NE(a, c);
    EXPECT_NEAR(double(sa.lost_random) / sa.submitted, 0.05 * (1 - 0.04), 0.01);
    EXPECT_GT(sa.lost_burst, 0u);
    EXPECT_GT(sa.reordered, 0u);
    EXPECT_FALSE(std::is_sorted(a.begin(), a.end()));
    EXPECT_EQ(sa.delivered, a.size());
}

TEST(NetFaults, BandwidthCapSerialisesAndDropsBeyondTheQueue) {
    FaultInjector f({.bandwidth_kbps = 800, .queue_bytes = 10000});  // 100 bytes per ms
    std::vector<uint8_t> d(1000), out;
    for (int i = 0; i < 20; ++i) f.submit(d, 0);
    EXPECT_EQ(f.stats().lost_queue, 10u);
    int delivered_by_5ms = 0;
    while (f.deliver(5000, out)) ++delivered_by_5ms;
    EXPECT_EQ(delivered_by_5ms, 0);  // the first needs 10 ms at 800 kbps
    int by_100ms = 0;
    while (f.deliver(100000, out)) ++by_100ms;
    EXPECT_EQ(by_100ms, 10);
}

TEST(NetRateLimit, HandshakesPerSourceAndGloballyAreBounded) {
    HandshakeRateLimiter r(
        {.per_second = 10, .burst = 10, .per_source_per_second = 1, .per_source_burst = 3});
    int allowed = 0;
    for (int i = 0; i < 100; ++i) allowed += r.allow(0x7f000001u, 0);
    EXPECT_EQ(allowed, 3);
    int others = 0;
    for (uint32_t a = 0; a < 100; ++a) others += r.allow(0x7f000100u + a, 0);
    EXPECT_EQ(others, 7);                          // the global bucket held 10
    EXPECT_TRUE(r.allow(0x7f000001u, 2'000'000));  // refilled
    r.penalise(0x7f000002u, 2'000'000);
    EXPECT_FALSE(r.allow(0x7f000002u, 2'000'000));
}

TEST(NetUdp, EndpointsParseAndOnlyLoopbackIsLoopback) {
    Endpoint e;
    ASSERT_TRUE(parse_endpoint("127.0.0.1:7000", e).ok());
    EXPECT_TRUE(e.loopback());
    ASSERT_TRUE(parse_endpoint("localhost:1", e).ok());
    EXPECT_TRUE(e.loopback());
    ASSERT_TRUE(parse_endpoint("10.0.0.1:80", e).ok());
    EXPECT_FALSE(e.loopback());
    EXPECT_FALSE(parse_endpoint("127.0.0.1", e).ok());
    EXPECT_FALSE(parse_endpoint("127.0.0.1:70000", e).ok());
    EXPECT_FALSE(parse_endpoint("example:80", e).ok());
}

TEST(NetGuessBudget, AnHourOfGuessingFromEverywhereGetsAtMost124Guesses) {
    GuessBudget b;
    int answered = 0;
    for (int64_t t = 0; t < int64_t(3600) * 1'000'000; t += 10'000) answered += b.start(t);
    EXPECT_LE(answered, 124);  // docs/protocol.md: a burst of 4, then one per 30 s at most
    EXPECT_GE(answered, 100);
    // A confirmed handshake gives its token back and ends the back-off.
    GuessBudget c;
    ASSERT_TRUE(c.start(0));
    c.confirmed(0);
    int at_once = 0;
    for (int i = 0; i < 10; ++i) at_once += c.start(0);
    EXPECT_EQ(at_once, 4);
    EXPECT_EQ(c.interval_s(), 16.0);
}

TEST(NetHandshake, ATicketReplacesThePinAndPaddingMustBeZero) {
    ResumptionTicket ticket;
    for (std::size_t i = 0; i < ticket.id.size(); ++i) ticket.id[i] = uint8_t(i + 1);
    for (std::size_t i = 0; i < ticket.secret.size(); ++i) ticket.secret[i] = uint8_t(3 * i);
    ticket.valid = true;
    ClientHandshake client;
    std::vector<uint8_t> hello, server_hello, finish;
    client.start("123456", hello, &ticket);
    ASSERT_EQ(hello.size(), kClientHelloSize);
    bool has_ticket = false;
    std::array<uint8_t, kTicketIdSize> id{};
    ASSERT_TRUE(client_hello_ticket(hello, has_ticket, id).ok());
    EXPECT_TRUE(has_ticket);
    EXPECT_EQ(id, ticket.id);
    PendingHandshake pending;
    SessionKeys keys;
    ASSERT_TRUE(answer_client_hello("123456", hello, server_hello, pending).ok());
    EXPECT_FALSE(client.finish(server_hello, finish, keys).ok()) << "the PIN is not the key";
    ASSERT_TRUE(answer_client_hello(ticket.secret_text(), hello, server_hello, pending).ok());
    ASSERT_TRUE(client.finish(server_hello, finish, keys).ok());
    EXPECT_TRUE(check_client_finish(pending, finish).ok());
    // Without a ticket the padding is zero; anything else there is refused.
    ClientHandshake plain;
    plain.start("123456", hello);
    ASSERT_TRUE(client_hello_ticket(hello, has_ticket, id).ok());
    EXPECT_FALSE(has_ticket);
    hello.back() = 1;
    EXPECT_FALSE(client_hello_ticket(hello, has_ticket, id).ok());
    // The Ticket message round-trips and refuses truncation.
    TicketMessage m{.id = ticket.id, .secret = ticket.secret}, back;
    std::vector<uint8_t> plain_text(kMaxPlaintext);
    plain_text.resize(encode(m, plain_text));
    ASSERT_TRUE(parse(plain_text, back).ok());
    EXPECT_EQ(back.secret, m.secret);
    plain_text.pop_back();
    EXPECT_FALSE(parse(plain_text, back).ok());
}
