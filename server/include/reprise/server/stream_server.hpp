#pragma once
// The streaming server: per authenticated session it renders the scene from the client's newest
// pose at the server's rate, encodes with the scene-aware codec, fragments with FEC and sends.
// Protocol: docs/protocol.md. Two threads: the network thread (handshakes, acks, keep-alives,
// sending) never waits for the render worker (renderer, encoders), which hands encoded frames
// over through a bounded queue per session; the worker adapts AA and rate to keep up.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "reprise/codec/codec.hpp"
#include "reprise/core/status.hpp"
#include "reprise/net/fragment.hpp"
#include "reprise/net/guess_budget.hpp"
#include "reprise/net/rate_limiter.hpp"
#include "reprise/net/udp.hpp"
#include "reprise/net/wire.hpp"
#include "reprise/server/rate_ladder.hpp"

namespace reprise::server {

struct StreamServerOptions {
    std::string scene = "pan";  // served when the client names none (a built-in name or a file)
    net::Endpoint listen{0x7f000001u, 0};
    std::string secret;  // PIN or token, 1..255 bytes
    double fps = 30.0;
    int width = 640, height = 360;
    // LowRes (Pajak et al. 2011): colour rendered at 1/lowres_factor of the pixels with a per-frame
    // jitter, depth and motion at full resolution; two codec streams per frame (docs/protocol.md).
    net::StreamMode mode = net::StreamMode::Full;
    int lowres_factor = 4;  // 2 or 4
    // Anti-aliased colour (RenderSettings::aa_samples): 1 renders a frame 4–6x faster on llvmpipe.
    int aa_samples = 4;
    int max_sessions = 4;
    bool loopback_only = false;  // refuse a non-loopback listen address (tests)
    // Depth to the precision the client's extrapolation needs: no pixel moves by more than a
    // quarter pixel for camera displacements up to 16.4 cm (docs/bitstream.md).
    codec::EncoderOptions encoder{.qp = 28, .depth = codec::DepthMode::View};
    // Bitrate adaptation: > 0 starts rate control there and moves it within [min, max] by the
    // client's loss reports; 0 keeps constant quality (encoder.qp).
    int bitrate_kbps = 0, min_bitrate_kbps = 100, max_bitrate_kbps = 50000;
    net::FecOptions fec;
    int max_in_flight_frames = 8;  // frames sent and not acknowledged before frames are skipped
    std::size_t send_queue_bytes = 1 << 20;  // per session; a frame that does not fit is skipped
    net::RateLimitOptions handshake_rate;
    net::GuessBudgetOptions guess_budget;  // PIN guesses, all sources together
    double session_timeout_s = 3.0;        // a session that sends nothing for this long ends
    int metrics_port = -1;  // >= 0: Prometheus text on 127.0.0.1:port (0: any free port)
    bool adapt = true;      // step AA samples and rate down when frames take longer than a period
    RateLadderOptions ladder;
    double render_delay_ms = 0.0;  // tests and benchmarks: a slower renderer (added per frame)
};

struct StreamServerStats {
    std::size_t sessions = 0;
    std::size_t sessions_total = 0;
    std::size_t handshakes_ok = 0, handshakes_failed = 0, handshakes_rate_limited = 0;
    std::size_t guesses_refused = 0;     // PIN hellos refused by the guessing budget
    std::size_t handshakes_resumed = 0;  // admitted by a resumption ticket
    std::size_t dropped_datagrams = 0;   // garbage, truncated, oversized, unauthenticated, replayed
    std::size_t frames_sent = 0, frames_skipped = 0;
    std::size_t frames_encoded = 0;
    std::size_t frames_dropped = 0;         // encoded, dropped from a full hand-over or send queue
    std::size_t frames_without_parity = 0;  // sent without FEC: no loss reported for 10 s
    std::size_t feedback_dropped = 0;       // acks or losses dropped from a full mailbox
    std::size_t refused_full = 0;           // handshakes answered "server full" (--max-sessions)
    std::size_t datagrams_sent = 0, bytes_sent = 0;
    std::size_t loss_reports = 0, key_frame_requests = 0, acks = 0;
    std::size_t max_queue_bytes = 0;  // largest send queue of any session
    double encode_ms_total = 0.0, render_ms_total = 0.0;
    // What the encoders wrote, summed over every frame encoded (both encoders in lowres mode).
    codec::StreamStats coded;
    double loss = 0.0;     // newest reported media loss fraction (any session)
    int bitrate_kbps = 0;  // newest target of the last session adapted
    // Rate adaptation (RateLadder): the current level (0 = as configured) and what it renders.
    int adapt_level = 0, adapt_levels = 1, aa_samples = 0;
    double fps = 0.0, frame_cost_ms = 0.0;
    std::size_t adapt_steps_down = 0, adapt_steps_up = 0;
};

class StreamServer {
public:
    // Binds the UDP socket (and the metrics listener); nothing is rendered until run().
    static Status create(const StreamServerOptions& options, std::unique_ptr<StreamServer>& server);
    ~StreamServer();

    // Serves until `stop` becomes true: the network on the calling thread, rendering and encoding
    // on a worker thread of its own (which creates the renderer).
    Status run(const std::atomic<bool>& stop);

    net::Endpoint local() const;
    int metrics_port() const;
    StreamServerStats stats() const;  // thread-safe snapshot

    struct State;

private:
    StreamServer();
    std::unique_ptr<State> state_;
};

// The scenes a client may name: the built-in scenes.
std::vector<std::string> scene_catalogue();

}  // namespace reprise::server
