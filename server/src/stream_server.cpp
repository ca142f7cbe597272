#include "reprise/server/stream_server.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <mutex>
#include <sstream>

#include "metrics_endpoint.hpp"
#include "reprise/net/guess_budget.hpp"
#include "reprise/net/secure.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"

namespace reprise::server {

namespace {

constexpr std::size_t kMaxPending = 32;
constexpr int64_t kPendingLifetimeUs = 5'000'000;
constexpr std::size_t kMaxTickets = 64;
constexpr int64_t kTicketLifetimeUs = 24 * 3600 * int64_t(1'000'000);
constexpr int64_t kInfoIntervalUs = 500'000;
constexpr int64_t kProbeIntervalUs =
    1'000'000;  // a stalled window still sends one frame this often

double ms_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

struct Pending {
    net::Endpoint peer;
    net::PendingHandshake handshake;
    std::vector<uint8_t> server_hello;
    int64_t created_us = 0;
    bool resumed = false;  // keyed by a ticket's secret, not the PIN
    std::array<uint8_t, net::kTicketIdSize> ticket_id{};
};

// A resumption ticket handed to an admitted client: its next handshake skips the PIN's budget.
struct IssuedTicket {
    net::TicketMessage ticket;
    int64_t issued_us = 0;
};

struct Session {
    net::Endpoint peer;
    net::SecureChannel channel;
    int64_t last_heard_us = 0, last_info_us = 0, last_progress_us = 0;
    bool started = false;
    std::string scene_name;
    Scene scene;
    CameraPath path;
    bool have_pose = false;
    net::PoseMessage pose;
    bool rendered_before = false;
    Instant previous;
    codec::Encoder encoder;
    codec::Encoder colour_encoder;  // lowres: the low-resolution colour stream
    Frame frame, low;
    Image<glm::vec4> low_color;
    codec::Packet packet, colour_packet;
    std::vector<uint8_t> bundle;
    int64_t frames_rendered = 0;
    std::deque<std::vector<uint8_t>> queue;  // sealed datagrams waiting for the socket
    std::size_t queue_bytes = 0;
    int64_t newest_sent = -1, newest_acked = -1;
    uint32_t report_received = 0, report_missing = 0;
    int bitrate_kbps = 0;
    int64_t min_rtt_us = 0;
    bool ended = false;
    net::TicketMessage ticket;  // for the client's next handshake, sent with every StreamInfo

    Session(net::Endpoint p, uint64_t connection, const net::SessionKeys& keys,
            const codec::EncoderOptions& eo)
        : peer(p),
          channel(connection, keys.server_to_client, keys.client_to_server),
          encoder(eo),
          colour_encoder(eo) {}
};

}  // namespace

struct StreamServer::State {
    StreamServerOptions options;
    net::UdpSocket socket;
    MetricsEndpoint metrics;
    net::HandshakeRateLimiter limiter;
    net::GuessBudget guesses;
    std::vector<Pending> pending;
    std::vector<IssuedTicket> tickets;
    std::vector<std::unique_ptr<Session>> sessions;
    std::unique_ptr<Renderer> renderer;
    // Scratch reused every datagram and frame.
    std::vector<uint8_t> datagram, plaintext, sealed, reply;
    std::vector<std::vector<uint8_t>> messages;
    std::vector<std::vector<uint8_t>> spare;
    mutable std::mutex stats_mutex;
    StreamServerStats stats;
    std::size_t sessions_total = 0;

    explicit State(const StreamServerOptions& o)
        : options(o), limiter(o.handshake_rate), guesses(o.guess_budget) {}

    void count(std::size_t StreamServerStats::*field, std::size_t n = 1) {
        std::lock_guard lock(stats_mutex);
        stats.*field += n;
    }

    void send_message(Session& s, std::span<const uint8_t> message) {
        s.channel.seal(message, sealed);
        std::vector<uint8_t> d;
        if (!spare.empty()) {
            d = std::move(spare.back());
            spare.pop_back();
        }
        d.assign(sealed.begin(), sealed.end());
        s.queue_bytes += d.size();
        s.queue.push_back(std::move(d));
    }

    void send_now(Session& s, std::span<const uint8_t> message) {
        send_message(s, message);
        flush(s);
    }

    void flush(Session& s) {
        std::size_t datagrams = 0, bytes = 0;
        while (!s.queue.empty()) {
            if (!socket.send_to(s.queue.front(), s.peer)) break;
            ++datagrams;
            bytes += s.queue.front().size();
            s.queue_bytes -= s.queue.front().size();
            spare.push_back(std::move(s.queue.front()));
            s.queue.pop_front();
        }
        if (spare.size() > 256) spare.resize(256);
        std::lock_guard lock(stats_mutex);
        stats.datagrams_sent += datagrams;
        stats.bytes_sent += bytes;
    }

    Session* find(uint64_t connection) {
        for (auto& s : sessions)
            if (s->channel.connection() == connection) return s.get();
        return nullptr;
    }

    void handle_datagram(std::span<const uint8_t> d, const net::Endpoint& from, int64_t now) {
        net::DatagramHeader h;
        if (d.size() > net::kMaxDatagram || !net::parse_header(d, h).ok()) {
            count(&StreamServerStats::dropped_datagrams);
            return;
        }
        switch (h.type) {
            case net::DatagramType::ClientHello:
                return client_hello(d, h, from, now);
            case net::DatagramType::ClientFinish:
                return client_finish(d, h, from, now);
            case net::DatagramType::Sealed:
                return sealed_datagram(d, h, from, now);
            default:
                count(&StreamServerStats::dropped_datagrams);
        }
    }

    // Every reply to an unauthenticated source is at most as large as what it sent: the size is
    // checked before any lookup, and a repeated hello (answered from memory) is rate limited too.
    void client_hello(std::span<const uint8_t> d, const net::DatagramHeader& h,
                      const net::Endpoint& from, int64_t now) {
        if (d.size() != net::kClientHelloSize) {
            count(&StreamServerStats::dropped_datagrams);
            return;
        }
        for (Pending& p : pending)
            if (p.handshake.connection == h.connection && p.peer == from) {
                if (!limiter.allow_source(from.address, now)) {
                    count(&StreamServerStats::handshakes_rate_limited);
                    return;
                }
                socket.send_to(p.server_hello, from);  // a retransmitted hello gets the same answer
                return;
            }
        if (find(h.connection) || int(sessions.size()) >= options.max_sessions) {
            count(&StreamServerStats::dropped_datagrams);
            return;
        }
        bool has_ticket = false;
        std::array<uint8_t, net::kTicketIdSize> ticket_id{};
        if (!net::client_hello_ticket(d, has_ticket, ticket_id).ok()) {
            count(&StreamServerStats::dropped_datagrams);
            return;
        }
        std::string ticket_secret;
        if (has_ticket) {
            const IssuedTicket* t = find_ticket(ticket_id, now);
            if (!t) {
                count(&StreamServerStats::dropped_datagrams);
                return;
            }
            ticket_secret.assign(t->ticket.secret.begin(), t->ticket.secret.end());
        } else if (!guesses.available(now)) {
            count(&StreamServerStats::guesses_refused);
            return;
        }
        if (!limiter.allow(from.address, now)) {
            count(&StreamServerStats::handshakes_rate_limited);
            return;
        }
        if (!has_ticket) guesses.start(now);  // an unfinished guess costs as a failed one
        Pending p;
        p.peer = from;
        p.created_us = now;
        p.resumed = has_ticket;
        p.ticket_id = ticket_id;
        if (!net::answer_client_hello(has_ticket ? ticket_secret : options.secret, d,
                                      p.server_hello, p.handshake)
                 .ok()) {
            count(&StreamServerStats::dropped_datagrams);
            return;
        }
        if (pending.size() >= kMaxPending) {
            auto oldest = std::min_element(
                pending.begin(), pending.end(),
                [](const Pending& a, const Pending& b) { return a.created_us < b.created_us; });
            pending.erase(oldest);
        }
        socket.send_to(p.server_hello, from);
        pending.push_back(std::move(p));
    }

    void client_finish(std::span<const uint8_t> d, const net::DatagramHeader& h,
                       const net::Endpoint& from, int64_t now) {
        if (d.size() != net::kClientFinishSize) {
            count(&StreamServerStats::dropped_datagrams);
            return;
        }
        auto it = std::find_if(pending.begin(), pending.end(), [&](const Pending& p) {
            return p.handshake.connection == h.connection && p.peer == from;
        });
        if (it == pending.end()) {
            count(&StreamServerStats::dropped_datagrams);
            return;
        }
        if (!net::check_client_finish(it->handshake, d).ok()) {
            limiter.penalise(from.address, now);
            pending.erase(it);
            count(&StreamServerStats::handshakes_failed);
            return;
        }
        if (it->resumed) {
            std::erase_if(tickets,
                          [&](const IssuedTicket& t) { return t.ticket.id == it->ticket_id; });
            count(&StreamServerStats::handshakes_resumed);
        } else {
            guesses.confirmed(now);
        }
        if (int(sessions.size()) >= options.max_sessions) {
            pending.erase(it);
            count(&StreamServerStats::dropped_datagrams);
            return;
        }
        codec::EncoderOptions eo = options.encoder;
        eo.fps = options.fps;
        eo.bitrate_kbps = options.bitrate_kbps;
        auto s = std::make_unique<Session>(from, h.connection, it->handshake.keys, eo);
        s->last_heard_us = s->last_progress_us = now;
        s->bitrate_kbps = options.bitrate_kbps;
        s->ticket = issue_ticket(now);
        pending.erase(it);
        sessions.push_back(std::move(s));
        ++sessions_total;
        count(&StreamServerStats::handshakes_ok);
    }

    const IssuedTicket* find_ticket(const std::array<uint8_t, net::kTicketIdSize>& id,
                                    int64_t now) {
        std::erase_if(tickets,
                      [&](const IssuedTicket& t) { return now - t.issued_us > kTicketLifetimeUs; });
        for (const IssuedTicket& t : tickets)
            if (t.ticket.id == id) return &t;
        return nullptr;
    }

    net::TicketMessage issue_ticket(int64_t now) {
        IssuedTicket t;
        t.issued_us = now;
        net::random_bytes(t.ticket.id);
        net::random_bytes(t.ticket.secret);
        if (tickets.size() >= kMaxTickets) tickets.erase(tickets.begin());  // the oldest
        tickets.push_back(t);
        return t.ticket;
    }

    void refuse(Session& s, const std::string& why) {
        reply.resize(net::kMaxPlaintext);
        reply.resize(net::encode_error(why, reply));
        send_now(s, reply);
        s.ended = true;
    }

    void start(Session& s, const net::StartMessage& m) {
        if (s.started) return;
        const std::string name = m.scene.empty() ? options.scene : m.scene;
        if (!m.scene.empty()) {
            const auto names = scene_catalogue();
            if (std::find(names.begin(), names.end(), name) == names.end())
                return refuse(s, "scene '" + name + "' is not in the catalogue");
        }
        if (Status st = load_scene(name, s.scene, s.path); !st.ok())
            return refuse(s, "scene: " + st.message());
        s.scene_name = m.scene.empty() ? std::string("default") : m.scene;
        s.started = true;
        send_info(s, net_now());
    }

    static int64_t net_now() { return net::now_us(); }

    void send_info(Session& s, int64_t now) {
        net::StreamInfoMessage info{.width = uint16_t(options.width),
                                    .height = uint16_t(options.height),
                                    .fps = float(options.fps),
                                    .mode = options.mode,
                                    .scene = s.scene_name};
        reply.resize(net::kMaxPlaintext);
        reply.resize(net::encode(info, reply));
        send_message(s, reply);
        reply.resize(net::kMaxPlaintext);
        reply.resize(net::encode(s.ticket, reply));
        send_now(s, reply);
        s.last_info_us = now;
    }

    void sealed_datagram(std::span<const uint8_t> d, const net::DatagramHeader& h,
                         const net::Endpoint& from, int64_t now) {
        Session* s = find(h.connection);
        if (!s || !(s->peer == from) || !s->channel.open(d, plaintext).ok()) {
            count(&StreamServerStats::dropped_datagrams);
            return;
        }
        s->last_heard_us = now;
        net::MessageType type;
        if (!net::message_type(plaintext, type).ok()) {
            count(&StreamServerStats::dropped_datagrams);
            return;
        }
        bool parsed = true;
        switch (type) {
            case net::MessageType::Start: {
                net::StartMessage m;
                parsed = net::parse(plaintext, m).ok();
                if (parsed) start(*s, m);
                break;
            }
            case net::MessageType::Pose: {
                net::PoseMessage m;
                parsed = net::parse(plaintext, m).ok();
                if (parsed && (!s->have_pose || m.sequence > s->pose.sequence)) {
                    s->pose = m;
                    s->have_pose = true;
                }
                break;
            }
            case net::MessageType::Ack: {
                net::AckMessage m;
                parsed = net::parse(plaintext, m).ok() && int64_t(m.frame) <= s->newest_sent;
                if (parsed) {
                    s->encoder.acknowledge(m.frame);
                    s->colour_encoder.acknowledge(m.frame);
                    s->newest_acked = std::max<int64_t>(s->newest_acked, m.frame);
                    s->last_progress_us = now;
                    count(&StreamServerStats::acks);
                }
                break;
            }
            case net::MessageType::LossReport: {
                net::LossReportMessage m;
                parsed = net::parse(plaintext, m).ok();
                if (parsed) {
                    for (int i = 0; i < m.count; ++i)
                        if (int64_t(m.frames[i]) <= s->newest_sent) {
                            s->encoder.report_loss(m.frames[i]);
                            s->colour_encoder.report_loss(m.frames[i]);
                        }
                    s->last_progress_us = now;
                    count(&StreamServerStats::loss_reports);
                }
                break;
            }
            case net::MessageType::KeyFrameRequest:
                parsed = plaintext.size() == 1;
                if (parsed) {
                    s->encoder.request_key_frame();
                    s->colour_encoder.request_key_frame();
                    s->last_progress_us = now;
                    count(&StreamServerStats::key_frame_requests);
                }
                break;
            case net::MessageType::ReceiverReport: {
                net::ReceiverReportMessage m;
                parsed = net::parse(plaintext, m).ok();
                if (parsed) adapt(*s, m);
                break;
            }
            case net::MessageType::Bye:
                s->ended = true;
                break;
            default:
                parsed = false;
        }
        if (!parsed) count(&StreamServerStats::dropped_datagrams);
    }

    // Loss over the interval since the previous report moves the rate-control target.
    void adapt(Session& s, const net::ReceiverReportMessage& m) {
        const uint32_t received = m.received - s.report_received,
                       missing = m.missing - s.report_missing;
        if (m.received < s.report_received || m.missing < s.report_missing) return;  // stale report
        s.report_received = m.received;
        s.report_missing = m.missing;
        if (received + missing == 0) return;
        const double loss = double(missing) / double(received + missing);
        if (m.rtt_us > 0)
            s.min_rtt_us = s.min_rtt_us > 0 ? std::min<int64_t>(s.min_rtt_us, m.rtt_us) : m.rtt_us;
        if (s.bitrate_kbps > 0) {
            // Loss-based as in WebRTC's GCC (above 10 % back off, below 2 % probe upwards, hold
            // between), plus a delay signal: a round trip grown 50 % over its minimum (queues
            // building up) backs off too.
            double next = s.bitrate_kbps;
            const bool queueing = s.min_rtt_us > 0 && m.rtt_us > s.min_rtt_us * 3 / 2 + 5000;
            if (loss > 0.10)
                next *= 1.0 - 0.5 * loss;
            else if (queueing)
                next *= 0.9;
            else if (loss < 0.02)
                next *= 1.05;
            s.bitrate_kbps =
                std::clamp(int(next), options.min_bitrate_kbps, options.max_bitrate_kbps);
            if (options.mode == net::StreamMode::LowRes) {
                // Geometry (depth + motion) and colour share the target by their usual weights.
                s.encoder.set_bitrate(std::max(1, s.bitrate_kbps * 2 / 3));
                s.colour_encoder.set_bitrate(std::max(1, s.bitrate_kbps / 3));
            } else {
                s.encoder.set_bitrate(s.bitrate_kbps);
            }
        }
        std::lock_guard lock(stats_mutex);
        stats.loss = loss;
        stats.bitrate_kbps = s.bitrate_kbps;
    }

    Status produce_frame(Session& s, int64_t now) {
        if (!s.started || !s.have_pose) return {};
        const bool window_full = s.newest_sent - s.newest_acked >= options.max_in_flight_frames;
        const bool probe = now - s.last_progress_us > kProbeIntervalUs;
        if (s.queue_bytes > options.send_queue_bytes / 2 || (window_full && !probe)) {
            count(&StreamServerStats::frames_skipped);
            return {};
        }
        if (probe) s.last_progress_us = now;
        const int w = options.width, h = options.height;
        Instant current = instant_on_path(s.path, s.scene, s.pose.scene_time, w, h);
        current.view = s.pose.view;
        Instant previous = current;
        previous.time = current.time - 1.0 / options.fps;
        if (s.rendered_before) previous.view = s.previous.view;
        auto t0 = std::chrono::steady_clock::now();
        const bool lowres = options.mode == net::StreamMode::LowRes;
        glm::vec2 jitter(0.0f);
        if (lowres)
            REPRISE_TRY(renderer->render_lowres(s.scene, current, previous,
                                                {.width = w, .height = h}, options.lowres_factor,
                                                s.frames_rendered, s.frame, s.low_color, jitter));
        else
            REPRISE_TRY(renderer->render(
                s.scene, current, previous,
                {.width = w, .height = h, .aa_samples = options.aa_samples}, s.frame));
        ++s.frames_rendered;
        s.frame.fps = options.fps;
        const double render_ms = ms_since(t0);
        s.previous = current;
        s.rendered_before = true;
        t0 = std::chrono::steady_clock::now();
        if (lowres) {
            make_colour_frame(s, jitter);
            // The geometry stream carries no colour: a constant that every prediction matches.
            std::fill(s.frame.color.data(), s.frame.color.data() + s.frame.color.pixel_count(),
                      glm::vec4(0.0f));
        }
        REPRISE_TRY(s.encoder.send_frame(s.frame));
        if (s.encoder.receive_packet(s.packet) != codec::Result::Ok)
            return Status::error("encoder gave no packet");
        std::span<const uint8_t> payload = s.packet.data;
        if (lowres) {
            REPRISE_TRY(s.colour_encoder.send_frame(s.low));
            if (s.colour_encoder.receive_packet(s.colour_packet) != codec::Result::Ok)
                return Status::error("colour encoder gave no packet");
            REPRISE_ASSERT(s.colour_packet.frame == s.packet.frame);
            bundle_packets(s.packet.data, s.colour_packet.data, s.bundle);
            payload = s.bundle;
        }
        const double encode_ms = ms_since(t0);
        if (payload.size() > net::kMaxPacketBytes) {
            s.encoder.report_loss(s.packet.frame);
            s.colour_encoder.report_loss(s.packet.frame);
            count(&StreamServerStats::frames_skipped);
            return {};
        }
        const std::size_t n = net::fragment_packet(payload, s.packet.frame, s.pose.client_time_us,
                                                   options.fec, messages);
        const std::size_t sealed_bytes =
            n * (net::kSealedHeaderSize + net::kAeadTagSize) + payload.size() * 2;
        if (s.queue_bytes + std::min(sealed_bytes, options.send_queue_bytes / 2) >
            options.send_queue_bytes) {
            s.encoder.report_loss(s.packet.frame);
            s.colour_encoder.report_loss(s.packet.frame);
            count(&StreamServerStats::frames_skipped);
            return {};
        }
        for (std::size_t i = 0; i < n; ++i) send_message(s, messages[i]);
        s.newest_sent = s.packet.frame;
        {
            std::lock_guard lock(stats_mutex);
            ++stats.frames_sent;
            stats.render_ms_total += render_ms;
            stats.encode_ms_total += encode_ms;
            stats.max_queue_bytes = std::max(stats.max_queue_bytes, s.queue_bytes);
        }
        flush(s);
        return {};
    }

    // The low-resolution colour as a frame of its own: depth and motion taken from the full
    // G-buffer at each low pixel's sample position (motion in low pixels), the camera's jitter
    // in low pixels, so the colour stream predicts by reprojection like any other.
    void make_colour_frame(Session& s, glm::vec2 jitter) {
        const int lw = s.low_color.width(), lh = s.low_color.height();
        const int w = s.frame.width(), h = s.frame.height();
        const glm::vec2 footprint(float(w) / float(lw), float(h) / float(lh));
        s.low.color.resize(lw, lh);
        s.low.depth.resize(lw, lh);
        s.low.motion.resize(lw, lh);
        std::copy(s.low_color.data(), s.low_color.data() + s.low_color.pixel_count(),
                  s.low.color.data());
        for (int v = 0; v < lh; ++v)
            for (int u = 0; u < lw; ++u) {
                const int x =
                    std::clamp(int(std::floor((u + 0.5f) * footprint.x + jitter.x)), 0, w - 1);
                const int y =
                    std::clamp(int(std::floor((v + 0.5f) * footprint.y + jitter.y)), 0, h - 1);
                s.low.depth(u, v) = s.frame.depth(x, y);
                s.low.motion(u, v) = s.frame.motion(x, y) / footprint;
            }
        s.low.camera = s.frame.camera;
        s.low.camera.jitter = jitter / footprint;
        s.low.fps = s.frame.fps;
    }

    // lowres: both codec packets of one frame in one unit (docs/protocol.md, "Low-resolution
    // mode").
    static void bundle_packets(std::span<const uint8_t> geometry, std::span<const uint8_t> colour,
                               std::vector<uint8_t>& out) {
        out.resize(1 + 4 + geometry.size() + 4 + colour.size());
        net::Writer w(out);
        w.u8(1);
        w.u32(uint32_t(geometry.size()));
        w.bytes(geometry);
        w.u32(uint32_t(colour.size()));
        w.bytes(colour);
    }

    std::string metrics_text() const {
        StreamServerStats st;
        {
            std::lock_guard lock(stats_mutex);
            st = stats;
        }
        std::ostringstream o;
        auto metric = [&](const char* name, const char* type, const char* help, double value) {
            o << "# HELP reprise_" << name << ' ' << help << "\n# TYPE reprise_" << name << ' '
              << type << "\nreprise_" << name << ' ' << value << '\n';
        };
        metric("sessions", "gauge", "Sessions connected.", double(st.sessions));
        metric("sessions_total", "counter", "Sessions admitted since start.",
               double(st.sessions_total));
        metric("handshakes_failed_total", "counter", "Key confirmations that failed.",
               double(st.handshakes_failed));
        metric("pin_guesses_refused_total", "counter",
               "Client hellos refused by the PIN's guessing budget.", double(st.guesses_refused));
        metric("handshakes_resumed_total", "counter", "Handshakes made with a resumption ticket.",
               double(st.handshakes_resumed));
        metric("handshakes_rate_limited_total", "counter",
               "Client hellos refused by the rate limit.", double(st.handshakes_rate_limited));
        metric("dropped_datagrams_total", "counter", "Datagrams dropped unread.",
               double(st.dropped_datagrams));
        metric("frames_sent_total", "counter", "Frames encoded and sent.", double(st.frames_sent));
        metric("frames_skipped_total", "counter", "Frames skipped (slow client or link).",
               double(st.frames_skipped));
        metric("bytes_sent_total", "counter", "UDP payload bytes sent.", double(st.bytes_sent));
        metric("fps", "gauge", "Configured server frame rate.", options.fps);
        metric("bitrate_target_kbps", "gauge", "Rate-control target of the last adapted session.",
               st.bitrate_kbps);
        metric("loss_ratio", "gauge", "Media loss the newest receiver report measured.", st.loss);
        metric("encode_ms_mean", "gauge", "Mean encode time per frame.",
               st.frames_sent ? st.encode_ms_total / double(st.frames_sent) : 0.0);
        metric("render_ms_mean", "gauge", "Mean render time per frame.",
               st.frames_sent ? st.render_ms_total / double(st.frames_sent) : 0.0);
        return o.str();
    }
};

std::vector<std::string> scene_catalogue() {
    std::vector<std::string> names;
    for (const SceneInfo& s : builtin_scenes()) names.emplace_back(s.name);
    return names;
}

StreamServer::StreamServer() = default;
StreamServer::~StreamServer() = default;

Status StreamServer::create(const StreamServerOptions& options,
                            std::unique_ptr<StreamServer>& server) {
    REPRISE_TRY(net::init_crypto());
    if (options.secret.empty() || options.secret.size() > 255)
        return Status::error("--pin: 1..255 characters");
    if (options.loopback_only && !options.listen.loopback())
        return Status::error("listen address " + options.listen.text() +
                             " is not loopback (127.0.0.0/8)");
    if (!(options.fps > 0.0 && options.fps <= 240.0))
        return Status::error("--fps must be in (0, 240]");
    if (options.width < 16 || options.height < 16 || options.width > 8192 || options.height > 8192)
        return Status::error("--size: each side 16..8192");
    if (options.max_sessions < 1 || options.max_sessions > 64)
        return Status::error("--max-sessions must be 1..64");
    if (options.mode == net::StreamMode::LowRes && !lowres_factor_valid(options.lowres_factor))
        return Status::error("--lowres must be 2 or 4");
    if (options.mode == net::StreamMode::LowRes && options.lowres_factor == 1)
        return Status::error("--lowres must be 2 or 4");
    std::unique_ptr<StreamServer> s(new StreamServer());
    s->state_ = std::make_unique<State>(options);
    REPRISE_TRY(s->state_->socket.bind(options.listen));
    if (options.metrics_port >= 0) REPRISE_TRY(s->state_->metrics.open(options.metrics_port));
    server = std::move(s);
    return {};
}

net::Endpoint StreamServer::local() const { return state_->socket.local(); }
int StreamServer::metrics_port() const { return state_->metrics.port(); }

StreamServerStats StreamServer::stats() const {
    std::lock_guard lock(state_->stats_mutex);
    return state_->stats;
}

Status StreamServer::run(const std::atomic<bool>& stop) {
    State& st = *state_;
    REPRISE_TRY(Renderer::create(st.renderer));
    const int64_t period = int64_t(1e6 / st.options.fps);
    int64_t next_tick = net::now_us();
    net::Endpoint from;
    while (!stop.load(std::memory_order_relaxed)) {
        int64_t now = net::now_us();
        st.socket.wait_readable(std::clamp<int64_t>(next_tick - now, 0, 5000));
        // Bounded per pass so a flood cannot starve the frame clock.
        for (int i = 0; i < 512 && st.socket.receive(st.datagram, from, net::kMaxDatagram); ++i)
            st.handle_datagram(st.datagram, from, net::now_us());
        now = net::now_us();
        if (now >= next_tick) {
            for (auto& s : st.sessions)
                if (Status failed = st.produce_frame(*s, now); !failed.ok()) {
                    std::fprintf(stderr, "[serve] session %s ended: %s\n", s->peer.text().c_str(),
                                 failed.message().c_str());
                    s->ended = true;
                }
            next_tick += period;
            if (next_tick < now) next_tick = now + period;
        }
        for (auto& s : st.sessions) {
            if (s->started && now - s->last_info_us > kInfoIntervalUs) st.send_info(*s, now);
            st.flush(*s);
        }
        std::erase_if(st.pending,
                      [&](const Pending& p) { return now - p.created_us > kPendingLifetimeUs; });
        const int64_t timeout = int64_t(st.options.session_timeout_s * 1e6);
        std::erase_if(st.sessions, [&](const std::unique_ptr<Session>& s) {
            return s->ended || now - s->last_heard_us > timeout;
        });
        {
            std::lock_guard lock(st.stats_mutex);
            st.stats.sessions = st.sessions.size();
            st.stats.sessions_total = st.sessions_total;
            for (auto& s : st.sessions)
                st.stats.max_queue_bytes = std::max(st.stats.max_queue_bytes, s->queue_bytes);
        }
        if (st.metrics.is_open()) st.metrics.serve(st.metrics_text());
    }
    // Tell the clients the session ended.
    for (auto& s : st.sessions) {
        st.reply.resize(net::kMaxPlaintext);
        st.reply.resize(net::encode_empty(net::MessageType::Bye, st.reply));
        st.send_now(*s, st.reply);
    }
    st.sessions.clear();
    st.renderer.reset();
    return {};
}

}  // namespace reprise::server
