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
#include "stream_session.hpp"
#include "stream_worker.hpp"

namespace reprise::server {

namespace {

constexpr std::size_t kMaxPending = 32;
constexpr int64_t kPendingLifetimeUs = 5'000'000;
constexpr std::size_t kMaxTickets = 64;
constexpr int64_t kTicketLifetimeUs = 24 * 3600 * int64_t(1'000'000);
constexpr int64_t kInfoIntervalUs = 500'000;
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

using detail::Session;

}  // namespace

struct StreamServer::State {
    StreamServerOptions options;
    net::UdpSocket socket;
    net::Waker waker;  // the worker wakes the network thread when it hands a frame over
    MetricsEndpoint metrics;
    net::HandshakeRateLimiter limiter;
    net::GuessBudget guesses;
    std::vector<Pending> pending;
    std::vector<IssuedTicket> tickets;
    // Written by the network thread only, under sessions_mutex; the worker copies it per tick.
    std::mutex sessions_mutex;
    std::vector<std::shared_ptr<Session>> sessions;
    // Scratch reused every datagram.
    std::vector<uint8_t> datagram, plaintext, sealed, reply;
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

    void send_message(Session::Net& s, std::span<const uint8_t> message) {
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

    void send_now(Session::Net& s, std::span<const uint8_t> message) {
        send_message(s, message);
        flush(s);
    }

    void flush(Session::Net& s) {
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

    // Seals and queues the frames the worker handed over; a frame that would overflow the send
    // queue is dropped and reported lost to the worker's encoders.
    void take_frames(Session& s) {
        std::deque<detail::EncodedFrame> frames;
        {
            std::lock_guard lock(s.mutex);
            frames.swap(s.box.frames);
        }
        std::size_t sent = 0, dropped = 0;
        for (detail::EncodedFrame& f : frames) {
            const std::size_t sealed_bytes =
                f.bytes + f.count * (net::kSealedHeaderSize + net::kAeadTagSize);
            if (s.net.queue_bytes + std::min(sealed_bytes, options.send_queue_bytes / 2) >
                options.send_queue_bytes) {
                std::lock_guard lock(s.mutex);
                detail::push_bounded(s.box.lost,
                                     f.frame);  // the worker drains it before its next frame
                ++dropped;
                continue;
            }
            for (std::size_t i = 0; i < f.count; ++i) send_message(s.net, f.messages[i]);
            s.net.newest_sent = f.frame;
            ++sent;
        }
        if (!frames.empty()) {
            std::lock_guard lock(s.mutex);
            for (detail::EncodedFrame& f : frames)
                if (s.box.spare.size() < detail::kMaxHandover + 1)
                    s.box.spare.push_back(std::move(f));
        }
        std::lock_guard lock(stats_mutex);
        stats.frames_sent += sent;
        stats.frames_dropped += dropped;
        stats.max_queue_bytes = std::max(stats.max_queue_bytes, s.net.queue_bytes);
    }

    Session* find(uint64_t connection) {
        for (auto& s : sessions)
            if (s->net.channel.connection() == connection) return s.get();
        return nullptr;
    }

    // "Server full" to an unauthenticated source: 14 bytes against its 128-byte hello or
    // 44-byte finish (no amplification), and at most the source's handshake rate.
    void refuse_full(const net::DatagramHeader& h, const net::Endpoint& from, int64_t now) {
        if (!limiter.allow_source(from.address, now)) {
            count(&StreamServerStats::handshakes_rate_limited);
            return;
        }
        std::array<uint8_t, net::kRefusedSize> out;
        const std::size_t n =
            net::encode(net::RefusedDatagram{.connection = h.connection,
                                             .reason = net::RefusalReason::ServerFull,
                                             .sessions = uint8_t(options.max_sessions)},
                        out);
        socket.send_to(std::span<const uint8_t>(out.data(), n), from);
        count(&StreamServerStats::refused_full);
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
        if (find(h.connection)) {
            count(&StreamServerStats::dropped_datagrams);
            return;
        }
        if (int(sessions.size()) >= options.max_sessions) return refuse_full(h, from, now);
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
            return refuse_full(h, from, now);
        }
        codec::EncoderOptions eo = options.encoder;
        eo.fps = options.fps;
        eo.bitrate_kbps = options.bitrate_kbps;
        auto s = std::make_shared<Session>(from, h.connection, it->handshake.keys, eo);
        s->net.last_heard_us = s->box.last_progress_us = now;
        s->net.bitrate_kbps = s->box.bitrate_kbps = options.bitrate_kbps;
        s->media.bitrate_kbps = options.bitrate_kbps;
        s->net.ticket = issue_ticket(now);
        pending.erase(it);
        {
            std::lock_guard lock(sessions_mutex);
            sessions.push_back(std::move(s));
        }
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
        send_now(s.net, reply);
        s.net.ended = true;
    }

    // The scene is checked against the catalogue here and loaded by the worker (a glTF file may
    // take a while); StreamInfo goes out at once.
    void start(Session& s, const net::StartMessage& m, int64_t now) {
        if (s.net.started) return;
        if (!m.scene.empty()) {
            const auto names = scene_catalogue();
            if (std::find(names.begin(), names.end(), m.scene) == names.end())
                return refuse(s, "scene '" + m.scene + "' is not in the catalogue");
        }
        s.net.scene_name = m.scene.empty() ? std::string("default") : m.scene;
        s.net.started = true;
        s.net.parity_until_us = now + detail::kParityAtStartUs;
        {
            std::lock_guard lock(s.mutex);
            s.box.started = true;
            s.box.scene = m.scene;
        }
        send_info(s.net, now);
    }

    void send_info(Session::Net& s, int64_t now) {
        float fps;
        {
            std::lock_guard lock(stats_mutex);
            fps = float(stats.fps);  // the rate adaptation's current rate
        }
        net::StreamInfoMessage info{.width = uint16_t(options.width),
                                    .height = uint16_t(options.height),
                                    .fps = fps,
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
        if (!s || !(s->net.peer == from) || !s->net.channel.open(d, plaintext).ok()) {
            count(&StreamServerStats::dropped_datagrams);
            return;
        }
        s->net.last_heard_us = now;
        net::MessageType type;
        if (!net::message_type(plaintext, type).ok()) {
            count(&StreamServerStats::dropped_datagrams);
            return;
        }
        bool parsed = true;
        std::size_t feedback_dropped = 0;
        switch (type) {
            case net::MessageType::Start: {
                net::StartMessage m;
                parsed = net::parse(plaintext, m).ok();
                if (parsed) start(*s, m, now);
                break;
            }
            case net::MessageType::Pose: {
                net::PoseMessage m;
                parsed = net::parse(plaintext, m).ok();
                std::lock_guard lock(s->mutex);
                if (parsed && (!s->box.have_pose || m.sequence > s->box.pose.sequence)) {
                    s->box.pose = m;
                    s->box.have_pose = true;
                }
                break;
            }
            case net::MessageType::Ack: {
                net::AckMessage m;
                parsed = net::parse(plaintext, m).ok() && int64_t(m.frame) <= s->net.newest_sent;
                if (parsed) {
                    std::lock_guard lock(s->mutex);
                    feedback_dropped += s->box.acked.size() >= detail::kMaxFeedback;
                    detail::push_bounded(s->box.acked, m.frame);
                    s->box.newest_acked = std::max<int64_t>(s->box.newest_acked, m.frame);
                    s->box.last_progress_us = now;
                }
                if (parsed) count(&StreamServerStats::acks);
                break;
            }
            case net::MessageType::LossReport: {
                net::LossReportMessage m;
                parsed = net::parse(plaintext, m).ok();
                if (parsed) {
                    s->net.parity_until_us = now + detail::kParityAfterLossUs;
                    std::lock_guard lock(s->mutex);
                    s->box.parity = true;
                    for (int i = 0; i < m.count; ++i)
                        if (int64_t(m.frames[i]) <= s->net.newest_sent) {
                            feedback_dropped += s->box.lost.size() >= detail::kMaxFeedback;
                            detail::push_bounded(s->box.lost, m.frames[i]);
                        }
                    s->box.last_progress_us = now;
                }
                if (parsed) count(&StreamServerStats::loss_reports);
                break;
            }
            case net::MessageType::KeyFrameRequest:
                parsed = plaintext.size() == 1;
                if (parsed) {
                    std::lock_guard lock(s->mutex);
                    s->box.key_frame = true;
                    s->box.last_progress_us = now;
                }
                if (parsed) count(&StreamServerStats::key_frame_requests);
                break;
            case net::MessageType::ReceiverReport: {
                net::ReceiverReportMessage m;
                parsed = net::parse(plaintext, m).ok();
                if (parsed) adapt(*s, m, now);
                break;
            }
            case net::MessageType::Bye:
                s->net.ended = true;
                break;
            default:
                parsed = false;
        }
        if (!parsed) count(&StreamServerStats::dropped_datagrams);
        if (feedback_dropped) count(&StreamServerStats::feedback_dropped, feedback_dropped);
    }

    // Loss over the interval since the previous report moves the rate-control target.
    // Parity protects frames while loss was seen recently: on a clean link it would cost up to a
    // copy of every frame of one fragment.
    void adapt(Session& session, const net::ReceiverReportMessage& m, int64_t now) {
        Session::Net& s = session.net;
        // `missing` (newest heard minus received) falls when a reordered datagram arrives late:
        // only an older `received` marks a stale report, and only a rise of missing counts (a
        // late datagram counted once while it was out may count again, a real loss never hides).
        if (m.received < s.report_received) return;
        const uint32_t received = m.received - s.report_received,
                       missing = m.missing > s.report_missing ? m.missing - s.report_missing : 0;
        s.report_received = m.received;
        s.report_missing = m.missing;
        if (missing > 0) s.parity_until_us = now + detail::kParityAfterLossUs;
        {
            std::lock_guard lock(session.mutex);
            session.box.parity = now < s.parity_until_us;
        }
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
            std::lock_guard lock(session.mutex);
            session.box.bitrate_kbps = s.bitrate_kbps;  // the worker sets its encoders
        }
        std::lock_guard lock(stats_mutex);
        stats.loss = loss;
        stats.bitrate_kbps = s.bitrate_kbps;
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
               st.frames_encoded ? st.encode_ms_total / double(st.frames_encoded) : 0.0);
        metric("render_ms_mean", "gauge", "Mean render time per frame.",
               st.frames_encoded ? st.render_ms_total / double(st.frames_encoded) : 0.0);
        metric("frames_dropped_total", "counter",
               "Frames encoded and dropped from a full hand-over or send queue.",
               double(st.frames_dropped));
        metric("frames_without_parity_total", "counter",
               "Frames sent without FEC parity (no loss reported for 10 s).",
               double(st.frames_without_parity));
        metric("feedback_dropped_total", "counter",
               "Acks or loss reports dropped from a full session mailbox.",
               double(st.feedback_dropped));
        metric("refused_full_total", "counter", "Handshakes refused: --max-sessions reached.",
               double(st.refused_full));
        metric("adapt_level", "gauge", "Rate adaptation level (0: as configured).",
               double(st.adapt_level));
        metric("adapt_aa_samples", "gauge", "Anti-aliasing samples rendered now.",
               double(st.aa_samples));
        metric("adapt_fps", "gauge", "Frame rate rendered now.", st.fps);
        metric("adapt_frame_cost_ms", "gauge", "Mean render + encode time of a frame tick.",
               st.frame_cost_ms);
        metric("adapt_steps_down_total", "counter", "Rate adaptation steps down.",
               double(st.adapt_steps_down));
        metric("adapt_steps_up_total", "counter", "Rate adaptation steps up.",
               double(st.adapt_steps_up));
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
    REPRISE_TRY(codec::check_encoder_options(options.encoder));
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
    // Render + encode on the worker; handshakes, feedback, keep-alives and sending here.
    detail::RenderWorker worker({.options = st.options,
                                 .sessions_mutex = st.sessions_mutex,
                                 .sessions = st.sessions,
                                 .stats_mutex = st.stats_mutex,
                                 .stats = st.stats,
                                 .waker = st.waker});
    worker.start();
    net::Endpoint from;
    while (!stop.load(std::memory_order_relaxed) && !worker.failed()) {
        st.socket.wait_readable(10'000, &st.waker);
        // Bounded per pass so a flood cannot starve the sessions' sending.
        for (int i = 0; i < 512 && st.socket.receive(st.datagram, from, net::kMaxDatagram); ++i)
            st.handle_datagram(st.datagram, from, net::now_us());
        const int64_t now = net::now_us();
        for (auto& s : st.sessions) {
            st.take_frames(*s);
            std::string failure;
            {
                std::lock_guard lock(s->mutex);
                failure = s->box.failure;
            }
            if (!failure.empty() && !s->net.ended) st.refuse(*s, failure);
            if (s->net.started && now - s->net.last_info_us > kInfoIntervalUs)
                st.send_info(s->net, now);
            st.flush(s->net);
            std::lock_guard lock(s->mutex);
            s->box.queue_bytes = s->net.queue_bytes;
        }
        std::erase_if(st.pending,
                      [&](const Pending& p) { return now - p.created_us > kPendingLifetimeUs; });
        const int64_t timeout = int64_t(st.options.session_timeout_s * 1e6);
        {
            std::lock_guard lock(st.sessions_mutex);
            std::erase_if(st.sessions, [&](const std::shared_ptr<Session>& s) {
                if (!s->net.ended && now - s->net.last_heard_us <= timeout) return false;
                std::lock_guard session_lock(s->mutex);
                s->box.ended = true;  // the worker may still hold it for this tick
                return true;
            });
        }
        {
            std::lock_guard lock(st.stats_mutex);
            st.stats.sessions = st.sessions.size();
            st.stats.sessions_total = st.sessions_total;
            for (auto& s : st.sessions)
                st.stats.max_queue_bytes = std::max(st.stats.max_queue_bytes, s->net.queue_bytes);
        }
        if (st.metrics.is_open()) st.metrics.serve(st.metrics_text());
    }
    worker.stop();
    // Tell the clients the session ended.
    for (auto& s : st.sessions) {
        st.reply.resize(net::kMaxPlaintext);
        st.reply.resize(net::encode_empty(net::MessageType::Bye, st.reply));
        st.send_now(s->net, st.reply);
    }
    {
        std::lock_guard lock(st.sessions_mutex);
        st.sessions.clear();
    }
    return worker.failed() ? worker.status() : Status{};
}

}  // namespace reprise::server
