#pragma once
// The streaming client: handshake, poses up, fragments down, reassembly with FEC, decoding, loss
// feedback, and every display frame extrapolated from the newest decoded frame to the newest
// local pose (latency hiding). Reconnects when the server goes silent. Protocol: docs/protocol.md.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "reprise/codec/codec.hpp"
#include "reprise/core/frame.hpp"
#include "reprise/core/status.hpp"
#include "reprise/net/fault_injector.hpp"
#include "reprise/net/secure.hpp"
#include "reprise/net/udp.hpp"
#include "reprise/net/wire.hpp"
#include "reprise/warp/fruc.hpp"
#include "reprise/warp/upsample.hpp"

namespace reprise::client {

struct StreamClientOptions {
    net::Endpoint server{0x7f000001u, 0};
    std::string secret;
    std::string scene;        // from the server's catalogue; empty: the server's default
    bool extrapolate = true;  // false: show the newest decoded frame (frame repetition)
    // How (warp, fill, a backend such as the GPU's: gpu::FrucBackend, which must outlive the
    // client and be used from the thread that calls display()); the mode is extrapolate.
    warp::FrucOptions extrapolation{.mode = warp::FrucMode::Extrapolate};
    // Lowres streams: where the colour is upsampled (null: the CPU; gpu::Upsampler, not owned,
    // used from the thread that calls poll()).
    warp::UpsampleBackend* upsampler = nullptr;
    // The upsampler keeps its output on its device (UpsampleBackend::output_kept) and the
    // extrapolation's backend takes it from there (gpu::Upsampler::keep_output with
    // gpu::FrucBackend::inputs_from, which takes the depth and motion that guided the upsampler
    // too): a decoded frame's colour comes to the CPU only for a reader
    // there (no extrapolation, a failed one, newest_decoded()). False: it always comes. Set before
    // streaming, with the two joined; otherwise the never-written CPU colour is warped.
    bool upsampled_colour_stays = false;
    bool inject_faults = false;  // put the in-process fault injector on both directions
    net::FaultOptions uplink, downlink;
    double reconnect_after_s = 2.0;  // silence from the server that ends the connection
    int max_auth_failures = 3;       // key confirmations failed in a row before giving up
    // From an earlier session with this server (StreamClient::ticket()): the handshake skips the
    // PIN's guessing budget; forgotten after one unanswered handshake (docs/protocol.md).
    net::ResumptionTicket ticket;
};

struct StreamClientStats {
    std::size_t connects = 0;  // sessions established (reconnects = connects - 1)
    std::size_t auth_failures = 0;
    std::size_t frames_decoded = 0, decode_errors = 0, frames_lost = 0;
    std::size_t key_frame_requests = 0;
    std::size_t datagrams_received = 0, datagrams_dropped = 0, bytes_received = 0;
    std::size_t fec_recovered = 0;
    // Frames a backend failed on (extrapolation: shown as decoded; upsampling: upsampled on the
    // CPU instead) and the last error.
    std::size_t backend_errors = 0;
    std::string backend_error;
    int64_t last_rtt_us = 0;   // pose sampled -> frame decoded
    std::string refused;       // the server's reason when it refused the session
    bool server_full = false;  // refused by the server's --max-sessions (docs/protocol.md)
};

// What one display frame was made from.
struct DisplayInfo {
    double scene_time = 0.0;     // the displayed instant
    int64_t pose_us = 0;         // when the displayed pose was sampled
    int64_t source_pose_us = 0;  // when the pose of the decoded frame was sampled
    double source_scene_time = 0.0;
    uint32_t source_frame = 0;  // codec frame number of the decoded frame
    bool extrapolated = false;
};

class StreamClient {
public:
    static Status create(const StreamClientOptions& options, std::unique_ptr<StreamClient>& client);
    ~StreamClient();

    // Network work due at `now_us`: handshake, retransmissions, receiving, decoding, feedback,
    // reconnecting. Returns an error only when the server keeps refusing (wrong PIN, bad scene).
    Status poll(int64_t now_us);
    // Waits until a datagram may be readable, at most `timeout_us`.
    void wait(int64_t timeout_us);
    // Sends the current pose (scene time in seconds, world -> camera).
    void send_pose(const glm::mat4& view, double scene_time, int64_t now_us);
    // The display frame for this pose: the newest decoded frame extrapolated to it (or shown as
    // it is without extrapolation), valid until the next call. Null before the first frame was
    // decoded.
    const GBufferView* display(const glm::mat4& view, double scene_time, int64_t pose_us,
                               DisplayInfo& info);

    bool connected() const;
    const net::StreamInfoMessage* stream_info()
        const;  // null before the server described the stream
    const StreamClientStats& stats() const;
    // The newest resumption ticket the server sent (valid once a session was admitted).
    const net::ResumptionTicket& ticket() const;
    // The newest decoded frame, its colour on the CPU (one the upsampler kept is downloaded
    // here: call it from the thread that calls poll(), and again after poll()).
    const codec::DecodedFrame* newest_decoded() const;

    struct State;

private:
    StreamClient();
    std::unique_ptr<State> state_;
};

// Drives a client for `duration_s` at `display_rate` Hz: each display tick samples the pose for
// scene time t (seconds since the start), sends it and shows the display frame to `show`.
// `pose` gives the world -> camera matrix at t; `show` may return false to stop early.
using PoseFunction = std::function<glm::mat4(double t)>;
using ShowFunction =
    std::function<bool(const GBufferView& frame, const DisplayInfo& info, int64_t displayed_us)>;
Status run_client(StreamClient& client, double duration_s, double display_rate,
                  const PoseFunction& pose, const ShowFunction& show);

}  // namespace reprise::client
