#pragma once
// One streaming session as the server's two threads see it (private to server/src). The network
// thread owns `net`, the render worker owns `media`; they talk only through `box` under `mutex`,
// held for copies and swaps, never while rendering, encoding or sending. Every list is bounded.
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "reprise/codec/codec.hpp"
#include "reprise/net/secure.hpp"
#include "reprise/net/wire.hpp"
#include "reprise/server/renderer.hpp"
#include "reprise/server/scene.hpp"

namespace reprise::server::detail {

// A scene as the worker keeps it: one object per name, so that the renderer keeps its textures
// while sessions showing the same scene take turns.
struct LoadedScene {
    Scene scene;
    CameraPath path;
};

constexpr std::size_t kMaxFeedback = 64;  // acks or losses waiting for the worker
constexpr std::size_t kMaxHandover = 2;   // encoded frames waiting for the network thread
// FEC parity for the first second of a session, and for 10 s after any loss reported.
constexpr int64_t kParityAtStartUs = 1'000'000, kParityAfterLossUs = 10'000'000;

// An encoded frame as plaintext Fragment messages, waiting to be sealed and sent.
struct EncodedFrame {
    uint32_t frame = 0;
    std::size_t count = 0;  // messages[0, count) are this frame's
    std::size_t bytes = 0;
    std::vector<std::vector<uint8_t>> messages;  // buffers reused through Mailbox::spare
};

struct Mailbox {
    // network -> worker
    bool started = false, ended = false;
    std::string scene;  // from the catalogue; empty: the server's default
    bool have_pose = false;
    net::PoseMessage pose;
    std::vector<uint32_t> acked, lost;  // each at most kMaxFeedback (the oldest dropped)
    bool key_frame = false;
    int bitrate_kbps = 0;
    bool parity = true;  // FEC parity with the frames (kParityAfterLossUs after a reported loss)
    int64_t newest_acked = -1, last_progress_us = 0;
    std::size_t queue_bytes = 0;  // sealed bytes waiting for the socket
    // worker -> network
    std::deque<EncodedFrame> frames;  // at most kMaxHandover (the oldest dropped, reported lost)
    std::vector<EncodedFrame> spare;  // sent frames back for reuse
    std::string failure;              // the worker cannot serve the session (scene, renderer)
};

// Keeps the newest kMaxFeedback entries.
inline void push_bounded(std::vector<uint32_t>& list, uint32_t frame) {
    if (list.size() >= kMaxFeedback) list.erase(list.begin());
    list.push_back(frame);
}

struct Session {
    struct Net {  // network thread only
        net::Endpoint peer;
        net::SecureChannel channel;
        int64_t last_heard_us = 0, last_info_us = 0;
        bool started = false, ended = false;
        std::string scene_name;
        std::deque<std::vector<uint8_t>> queue;  // sealed datagrams waiting for the socket
        std::size_t queue_bytes = 0;
        int64_t newest_sent = -1;
        uint32_t report_received = 0, report_missing = 0;
        int bitrate_kbps = 0;
        int64_t min_rtt_us = 0;
        int64_t parity_until_us = 0;  // FEC parity is sent until then
        net::TicketMessage ticket;    // for the client's next handshake, sent with every StreamInfo
    } net;
    struct Media {                                 // render worker only
        std::shared_ptr<const LoadedScene> scene;  // shared by the sessions that show it
        bool rendered_before = false;
        Instant previous;
        codec::Encoder encoder, color_encoder;  // lowres: the low-resolution colour stream
        Frame frame, low;  // low: lowres depth and motion at the colour samples (no colour)
        Image<glm::vec4> low_color;
        codec::Packet packet, color_packet;
        std::vector<uint8_t> bundle;
        int64_t frames_rendered = 0, newest_encoded = -1;
        int bitrate_kbps = 0;
        std::vector<uint32_t> acked, lost;                 // swapped out of the mailbox
        explicit Media(const codec::EncoderOptions& eo) {  // checked by StreamServer::create
            REPRISE_ASSERT(codec::Encoder::create(eo, encoder).ok() &&
                           codec::Encoder::create(eo, color_encoder).ok());
        }
    } media;
    std::mutex mutex;
    Mailbox box;

    Session(net::Endpoint peer, uint64_t connection, const net::SessionKeys& keys,
            const codec::EncoderOptions& eo)
        : media(eo) {
        net.peer = peer;
        net.channel = net::SecureChannel(connection, keys.server_to_client, keys.client_to_server);
    }
};

}  // namespace reprise::server::detail
