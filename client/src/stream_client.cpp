#include "reprise/client/stream_client.hpp"

#include <algorithm>
#include <cmath>

#include "reprise/codec/codec.hpp"
#include "reprise/net/fragment.hpp"
#include "reprise/net/secure.hpp"
#include "reprise/warp/extrapolate.hpp"
#include "reprise/warp/upsample.hpp"

namespace reprise::client {

namespace {

constexpr int64_t kHelloRetryUs = 250'000;
constexpr int64_t kHandshakeGiveUpUs = 3'000'000;
constexpr int64_t kReportIntervalUs = 100'000;
constexpr int64_t kKeyRequestIntervalUs = 300'000;
// After a reported loss the frames already on their way still fail to decode, until the server
// predicts from a frame this client holds: a key frame is asked for only when failures last
// longer than two round trips and this.
constexpr int64_t kDecodeErrorGraceUs = 100'000;

enum class Phase { Idle, HelloSent, Finished, Streaming };

}  // namespace

struct StreamClient::State {
    StreamClientOptions options;
    net::UdpSocket socket;
    net::FaultInjector uplink, downlink;
    Phase phase = Phase::Idle;
    net::ClientHandshake handshake;
    net::SecureChannel channel;
    std::vector<uint8_t> hello, finish_datagram;
    int64_t phase_started_us = 0, last_sent_hello_us = 0, last_heard_us = 0, last_report_us = 0,
            last_key_request_us = -1'000'000'000;
    net::StreamInfoMessage info;
    bool have_info = false;
    std::unique_ptr<net::Reassembler> reassembler;
    std::unique_ptr<codec::Decoder> decoder;
    std::unique_ptr<codec::Decoder> color_decoder;  // lowres: the low-resolution colour stream
    bool colorless_decoder = false;                 // `decoder` leaves colour out (lowres)
    codec::DecodedFrame low_decoded;
    Image<glm::vec4> upsampled;
    warp::SpatioTemporalUpsampler upsampler;
    int64_t newest_completed = -1;
    int consecutive_decode_errors = 0;
    int64_t first_decode_error_us = 0;  // of the current run of failures
    uint64_t received_sealed = 0;
    // Decoded frames read the decoder's pictures in place (no copy of depth and motion).
    codec::DecodedFrame decoded, scratch_decoded;
    Frame displayed;
    GBufferView shown;
    bool have_decoded = false;
    bool decoded_colour_kept = false;  // its colour is still the upsampler's (on its device)
    int64_t decoded_pose_us = 0;
    uint32_t decoded_frame = 0;
    uint64_t decoded_count = 0;  // frames decoded: the extrapolator's key for the one shown
    warp::PoseExtrapolator extrapolator;
    uint32_t pose_sequence = 0;
    StreamClientStats stats;
    std::vector<uint8_t> datagram, plaintext, sealed, message;
    std::vector<uint32_t> abandoned;

    net::ResumptionTicket ticket;  // from the newest session: the next handshake skips the PIN
    bool resuming = false;

    State(const StreamClientOptions& o)
        : options(o),
          uplink(o.uplink),
          downlink(o.downlink),
          extrapolator(o.extrapolation),
          ticket(o.ticket) {}

    // A ticket the server no longer knows (restarted, expired) costs one handshake time-out.
    void forget_ticket() {
        if (resuming) ticket.valid = false;
        resuming = false;
    }

    void transmit(std::span<const uint8_t> d, int64_t now) {
        if (options.inject_faults)
            uplink.submit(d, now);
        else
            socket.send_to(d, options.server);
    }

    void send_sealed(std::span<const uint8_t> plain, int64_t now) {
        channel.seal(plain, sealed);
        transmit(sealed, now);
    }

    void start_handshake(int64_t now) {
        resuming = ticket.valid;
        handshake.start(options.secret, hello, resuming ? &ticket : nullptr);
        phase = Phase::HelloSent;
        phase_started_us = last_sent_hello_us = now;
        transmit(hello, now);
    }

    void reset_stream() {
        reassembler = std::make_unique<net::Reassembler>();
        decoder = std::make_unique<codec::Decoder>();
        colorless_decoder = false;
        color_decoder = std::make_unique<codec::Decoder>();
        upsampler.reset();
        if (options.upsampler) options.upsampler->reset();
        newest_completed = -1;
        consecutive_decode_errors = 0;
        received_sealed = 0;
        have_info = false;
    }

    void send_start(int64_t now) {
        message.resize(net::kMaxPlaintext);
        message.resize(net::encode(net::StartMessage{.scene = options.scene}, message));
        send_sealed(message, now);
    }

    void report_lost(const std::vector<uint32_t>& frames, int64_t now) {
        for (std::size_t i = 0; i < frames.size(); i += net::kMaxLossReport) {
            net::LossReportMessage m;
            m.count = uint8_t(std::min(net::kMaxLossReport, frames.size() - i));
            for (int k = 0; k < m.count; ++k) m.frames[k] = frames[i + k];
            message.resize(net::kMaxPlaintext);
            message.resize(net::encode(m, message));
            send_sealed(message, now);
        }
        stats.frames_lost += frames.size();
    }

    // The decoded frame's colour on the CPU: where the upsampler kept it, downloaded now.
    void bring_colour() {
        if (!decoded_colour_kept) return;
        decoded_colour_kept = false;
        const Status s = options.upsampler->download_kept(decoded.color.view());
        if (!s.ok()) {  // shown black rather than another frame's pixels
            ++stats.backend_errors;
            stats.backend_error = s.message();
            decoded.color.fill(glm::vec4(0.0f));
        }
    }

    void request_key(int64_t now) {
        if (now - last_key_request_us < kKeyRequestIntervalUs) return;
        last_key_request_us = now;
        message.resize(net::kMaxPlaintext);
        message.resize(net::encode_empty(net::MessageType::KeyFrameRequest, message));
        send_sealed(message, now);
        ++stats.key_frame_requests;
    }

    void on_packet(const net::Reassembled& packet, int64_t now) {
        // Frames between the previous completed one and this one will never come.
        abandoned.clear();
        for (int64_t f = newest_completed + 1; f < int64_t(packet.frame) && abandoned.size() < 64;
             ++f)
            abandoned.push_back(uint32_t(f));
        if (!abandoned.empty()) report_lost(abandoned, now);
        newest_completed = packet.frame;
        const bool lowres = have_info && info.mode == net::StreamMode::LowRes;
        std::span<const uint8_t> geometry = packet.data, color;
        bool ok = !lowres || split_bundle(packet.data, geometry, color);
        // lowres: the colour buffer of the frame handed back to the decoder (which makes none)
        // stays here for the next upsampling.
        if (lowres && upsampled.empty()) std::swap(upsampled, scratch_decoded.color);
        ok = ok && decoder->send_packet(geometry).ok() &&
             decoder->receive_frame(scratch_decoded) == Result::Ok;
        if (ok && lowres)
            ok = color_decoder->send_packet(color).ok() &&
                 color_decoder->receive_frame(low_decoded) == Result::Ok;
        if (!ok) {
            ++stats.decode_errors;
            abandoned.assign(1, packet.frame);
            report_lost(abandoned, now);
            if (consecutive_decode_errors++ == 0) first_decode_error_us = now;
            if (consecutive_decode_errors >= 2 &&
                now - first_decode_error_us > 2 * stats.last_rtt_us + kDecodeErrorGraceUs)
                request_key(now);
            return;
        }
        if (lowres) {
            // Herzog 2010: the low-resolution colour to full resolution, guided by the decoded
            // full-resolution depth and motion; the jitter comes with the colour stream's camera.
            const int w = scratch_decoded.width(), h = scratch_decoded.height();
            const glm::vec2 footprint(float(w) / float(low_decoded.color.width()),
                                      float(h) / float(low_decoded.color.height()));
            const GBufferView guides{.depth = scratch_decoded.depth(),
                                     .motion = scratch_decoded.motion(),
                                     .camera = scratch_decoded.camera};
            upsampled.resize(w, h);
            const glm::vec2 jitter = low_decoded.camera.jitter * footprint;
            bool done = false;
            if (options.upsampler) {
                const Status on_backend = options.upsampler->upsample(
                    low_decoded.color.view(), jitter, guides, upsampled.view());
                done = on_backend.ok();
                if (!done) {  // neither history follows on from this frame: both start over
                    ++stats.backend_errors;
                    stats.backend_error = on_backend.message();
                    options.upsampler->reset();
                    upsampler.reset();
                }
            }
            if (!done)
                upsampler.upsample(low_decoded.color.view(), jitter, guides, upsampled.view());
            std::swap(upsampled, scratch_decoded.color);
        }
        consecutive_decode_errors = 0;
        std::swap(decoded, scratch_decoded);
        decoded_colour_kept = lowres && options.upsampler && options.upsampler->output_kept();
        // A frame not upsampled there (a full-resolution stream now): what the upsampler keeps
        // of a frame (its output, its guides), named by the images it was made for, must not
        // outlive those images' reuse by the decoder.
        if (!lowres && options.upsampler) options.upsampler->reset();
        have_decoded = true;
        decoded_pose_us = packet.pose_time_us;
        decoded_frame = packet.frame;
        ++decoded_count;
        ++stats.frames_decoded;
        stats.last_rtt_us = now - packet.pose_time_us;
        message.resize(net::kMaxPlaintext);
        message.resize(net::encode(net::AckMessage{.frame = packet.frame}, message));
        send_sealed(message, now);
    }

    // lowres bundle: u8 version 1, u32 n, n bytes geometry packet, u32 m, m bytes colour packet.
    static bool split_bundle(std::span<const uint8_t> bundle, std::span<const uint8_t>& geometry,
                             std::span<const uint8_t>& color) {
        net::Reader r(bundle);
        if (r.u8() != 1) return false;
        geometry = r.bytes(r.u32());
        color = r.bytes(r.u32());
        return r.ok() && r.remaining() == 0 && !geometry.empty() && !color.empty();
    }

    void on_datagram(std::span<const uint8_t> d, int64_t now) {
        net::DatagramHeader h;
        if (!net::parse_header(d, h).ok()) {
            ++stats.datagrams_dropped;
            return;
        }
        if (h.type == net::DatagramType::Refused) {
            // Unauthenticated, so only for the handshake under way (its random connection id).
            net::RefusedDatagram r;
            if ((phase == Phase::HelloSent || phase == Phase::Finished) &&
                h.connection == handshake.connection() && net::parse(d, r).ok()) {
                stats.server_full = true;
                stats.refused = "server full: " + std::to_string(r.sessions) + " sessions";
                phase = Phase::Idle;
            } else {
                ++stats.datagrams_dropped;
            }
            return;
        }
        if (h.type == net::DatagramType::ServerHello) {
            if (phase != Phase::HelloSent) return;
            net::SessionKeys keys;
            if (Status s = handshake.finish(d, finish_datagram, keys); !s.ok()) {
                if (h.connection == handshake.connection()) {
                    if (!resuming) ++stats.auth_failures;
                    forget_ticket();
                    phase = Phase::Idle;
                }
                ++stats.datagrams_dropped;
                return;
            }
            channel = net::SecureChannel(handshake.connection(), keys.client_to_server,
                                         keys.server_to_client);
            phase = Phase::Finished;
            phase_started_us = last_sent_hello_us = now;
            stats.auth_failures = 0;
            reset_stream();
            transmit(finish_datagram, now);
            send_start(now);
            return;
        }
        if (h.type != net::DatagramType::Sealed || phase < Phase::Finished ||
            !channel.open(d, plaintext).ok()) {
            ++stats.datagrams_dropped;
            return;
        }
        ++received_sealed;
        ++stats.datagrams_received;
        stats.bytes_received += d.size();
        last_heard_us = now;
        net::MessageType type;
        if (!net::message_type(plaintext, type).ok()) return;
        switch (type) {
            case net::MessageType::StreamInfo: {
                net::StreamInfoMessage m;
                if (!net::parse(plaintext, m).ok()) return;
                info = m;
                have_info = true;
                // lowres: the full-resolution stream's colour is never shown (the upsampled
                // low-resolution colour is): its decoder leaves it out.
                if (const bool lowres = m.mode == net::StreamMode::LowRes;
                    lowres != colorless_decoder) {
                    decoder = std::make_unique<codec::Decoder>();
                    REPRISE_ASSERT(codec::Decoder::create({.color = !lowres}, *decoder).ok());
                    colorless_decoder = lowres;
                }
                if (phase == Phase::Finished) {
                    phase = Phase::Streaming;
                    ++stats.connects;
                }
                break;
            }
            case net::MessageType::Fragment: {
                net::FragmentMessage m;
                if (!net::parse(plaintext, m).ok()) return;
                net::Reassembled packet;
                abandoned.clear();
                const bool done = reassembler->add(m, packet, abandoned);
                if (!abandoned.empty()) report_lost(abandoned, now);
                if (done) on_packet(packet, now);
                stats.fec_recovered = reassembler->stats().recovered;
                break;
            }
            case net::MessageType::Error: {
                std::string text;
                if (net::parse_error(plaintext, text).ok()) stats.refused = text;
                phase = Phase::Idle;
                break;
            }
            case net::MessageType::Ticket: {
                net::TicketMessage m;
                if (!net::parse(plaintext, m).ok()) return;
                ticket.id = m.id;
                ticket.secret = m.secret;
                ticket.valid = true;
                break;
            }
            case net::MessageType::Bye:
                phase = Phase::Idle;
                break;
            default:
                break;
        }
    }

    void send_report(int64_t now) {
        const uint64_t newest = channel.newest_received();
        net::ReceiverReportMessage m{
            .received = uint32_t(received_sealed),
            .missing = uint32_t(newest > received_sealed ? newest - received_sealed : 0),
            .rtt_us = uint32_t(std::clamp<int64_t>(stats.last_rtt_us, 0, 1'000'000'000))};
        message.resize(net::kMaxPlaintext);
        message.resize(net::encode(m, message));
        send_sealed(message, now);
        last_report_us = now;
    }
};

StreamClient::StreamClient() = default;
StreamClient::~StreamClient() = default;

Status StreamClient::create(const StreamClientOptions& options,
                            std::unique_ptr<StreamClient>& client) {
    REPRISE_TRY(net::init_crypto());
    if (options.secret.empty() || options.secret.size() > 255)
        return Status::error("--pin: 1..255 characters");
    if (!options.scene.empty() && !net::valid_scene_name(options.scene))
        return Status::error("--scene: a catalogue name (1..32 of [a-z0-9_-]), never a path");
    if (options.server.port == 0) return Status::error("server address: port 0");
    warp::FrucOptions extrapolation = options.extrapolation;
    extrapolation.mode = warp::FrucMode::Extrapolate;
    REPRISE_TRY(warp::check_fruc_options(extrapolation));
    std::unique_ptr<StreamClient> c(new StreamClient());
    c->state_ = std::make_unique<State>(options);
    REPRISE_TRY(c->state_->socket.bind({options.server.loopback() ? 0x7f000001u : 0u, 0}));
    client = std::move(c);
    return {};
}

Status StreamClient::poll(int64_t now) {
    State& s = *state_;
    if (s.stats.auth_failures >= std::size_t(s.options.max_auth_failures))
        return Status::error("the server rejected the key confirmation " +
                             std::to_string(s.stats.auth_failures) + " times (wrong PIN?)");
    if (!s.stats.refused.empty())
        return Status::error("the server refused the session: " + s.stats.refused);
    // Uplink faults: datagrams leave when the simulated link delivers them.
    if (s.options.inject_faults)
        while (s.uplink.deliver(now, s.datagram)) s.socket.send_to(s.datagram, s.options.server);
    net::Endpoint from;
    for (int i = 0; i < 4096 && s.socket.receive(s.datagram, from, net::kMaxDatagram); ++i) {
        if (!(from == s.options.server)) continue;
        if (s.options.inject_faults)
            s.downlink.submit(s.datagram, now);
        else
            s.on_datagram(s.datagram, now);
    }
    if (s.options.inject_faults)
        while (s.downlink.deliver(now, s.datagram)) s.on_datagram(s.datagram, now);

    switch (s.phase) {
        case Phase::Idle:
            s.start_handshake(now);
            break;
        case Phase::HelloSent:
            if (now - s.phase_started_us > kHandshakeGiveUpUs) {
                s.forget_ticket();
                s.start_handshake(now);
            } else if (now - s.last_sent_hello_us > kHelloRetryUs) {
                s.last_sent_hello_us = now;
                s.transmit(s.hello, now);
            }
            break;
        case Phase::Finished:
            if (now - s.phase_started_us > kHandshakeGiveUpUs)
                s.start_handshake(now);
            else if (now - s.last_sent_hello_us > kHelloRetryUs) {
                s.last_sent_hello_us = now;
                s.transmit(s.finish_datagram, now);
                s.send_start(now);
            }
            break;
        case Phase::Streaming:
            if (now - s.last_heard_us > int64_t(s.options.reconnect_after_s * 1e6))
                s.start_handshake(now);
            else if (now - s.last_report_us > kReportIntervalUs)
                s.send_report(now);
            break;
    }
    return {};
}

void StreamClient::wait(int64_t timeout_us) {
    State& s = *state_;
    if (s.options.inject_faults) {
        const int64_t due = std::min(
            s.uplink.next_due(net::now_us()) < 0 ? timeout_us : s.uplink.next_due(net::now_us()),
            s.downlink.next_due(net::now_us()) < 0 ? timeout_us
                                                   : s.downlink.next_due(net::now_us()));
        timeout_us = std::min(timeout_us, due);
    }
    if (timeout_us > 0) s.socket.wait_readable(timeout_us);
}

void StreamClient::send_pose(const glm::mat4& view, double scene_time, int64_t now_us) {
    State& s = *state_;
    if (s.phase != Phase::Streaming) return;
    net::PoseMessage m{.sequence = ++s.pose_sequence,
                       .client_time_us = now_us,
                       .scene_time = scene_time,
                       .view = view};
    s.message.resize(net::kMaxPlaintext);
    s.message.resize(net::encode(m, s.message));
    s.send_sealed(s.message, now_us);
}

const GBufferView* StreamClient::display(const glm::mat4& view, double scene_time, int64_t pose_us,
                                         DisplayInfo& info) {
    State& s = *state_;
    if (!s.have_decoded) return nullptr;
    const codec::DecodedFrame& f = s.decoded;
    info.scene_time = scene_time;
    info.pose_us = pose_us;
    info.source_pose_us = s.decoded_pose_us;
    info.source_scene_time = f.camera.time;
    info.source_frame = s.decoded_frame;
    info.extrapolated = s.options.extrapolate;
    if (!s.options.extrapolate || !s.options.upsampled_colour_stays) s.bring_colour();
    if (!s.options.extrapolate) {
        s.shown = f.view();
        return &s.shown;
    }
    const double fps = s.have_info ? s.info.fps : (f.fps > 0 ? f.fps : 30.0);
    const float periods = float(std::clamp((scene_time - f.camera.time) * fps, 0.0, 8.0));
    const Status made = s.extrapolator.extrapolate(f.view(), view, f.camera.projection, periods,
                                                   s.displayed, s.decoded_count);
    if (!made.ok()) {  // the backend failed: the decoded frame as it is
        ++s.stats.backend_errors;
        s.stats.backend_error = made.message();
        s.bring_colour();
        info.extrapolated = false;
        s.shown = f.view();
        return &s.shown;
    }
    s.displayed.camera.time = scene_time;
    s.displayed.fps = f.fps;
    s.shown = s.displayed.view();
    return &s.shown;
}

bool StreamClient::connected() const { return state_->phase == Phase::Streaming; }
const net::StreamInfoMessage* StreamClient::stream_info() const {
    return state_->have_info ? &state_->info : nullptr;
}
const StreamClientStats& StreamClient::stats() const { return state_->stats; }
const net::ResumptionTicket& StreamClient::ticket() const { return state_->ticket; }
const codec::DecodedFrame* StreamClient::newest_decoded() const {
    state_->bring_colour();
    return state_->have_decoded ? &state_->decoded : nullptr;
}

Status run_client(StreamClient& client, double duration_s, double display_rate,
                  const PoseFunction& pose, const ShowFunction& show) {
    if (!(display_rate > 0 && display_rate <= 1000))
        return Status::error("--display-rate must be in (0, 1000]");
    if (!(duration_s > 0 && duration_s <= 1e6))
        return Status::error("--duration must be in (0, 1e6]");
    const int64_t start = net::now_us();
    const int64_t period = int64_t(1e6 / display_rate);
    int64_t tick = 0;
    DisplayInfo info;
    for (;;) {
        int64_t now = net::now_us();
        const int64_t due = start + tick * period;
        if (now < due) {
            client.wait(std::min<int64_t>(due - now, 2000));
            REPRISE_TRY(client.poll(net::now_us()));
            continue;
        }
        const double t = double(tick) / display_rate;
        if (t >= duration_s) break;
        ++tick;
        // Late ticks are dropped, not queued: the display shows the newest state.
        if (now - due > period) tick = (now - start) / period + 1;
        REPRISE_TRY(client.poll(now));
        const glm::mat4 view = pose(t);
        const int64_t sampled = net::now_us();
        client.send_pose(view, t, sampled);
        if (const GBufferView* f = client.display(view, t, sampled, info))
            if (!show(*f, info, net::now_us())) break;
    }
    return {};
}

}  // namespace reprise::client
