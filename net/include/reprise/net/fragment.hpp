#pragma once
// Codec packets split into datagram-sized fragments with XOR parity per group (forward error
// correction: any one lost fragment per group is rebuilt), and put back together on the other
// side in a bounded number of bounded slots.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "reprise/core/status.hpp"
#include "reprise/net/wire.hpp"

namespace reprise::net {

struct FecOptions {
    int group = 8;  // data fragments per XOR parity fragment (overhead 1/group); 0 = no parity
    std::size_t fragment_payload = 1100;  // bytes per fragment, at most kMaxFragmentPayload
};

constexpr std::size_t kMaxPacketBytes = std::size_t(4) << 20;  // largest codec packet sent
constexpr std::size_t kMaxFragments = 8192;

// Writes the fragment messages (plaintext, ready to seal) of one packet into `messages`
// (reused: its buffers keep their capacity). Returns the number of messages.
std::size_t fragment_packet(std::span<const uint8_t> packet, uint32_t frame, int64_t pose_time_us,
                            const FecOptions& options, std::vector<std::vector<uint8_t>>& messages);

struct ReassemblerOptions {
    int slots = 4;  // packets being reassembled at once
    std::size_t max_packet_bytes = kMaxPacketBytes;
};

struct ReassemblyStats {
    std::size_t fragments = 0;
    std::size_t recovered = 0;  // data fragments rebuilt from parity
    std::size_t duplicates = 0;
    std::size_t stale = 0;         // for packets already delivered or given up
    std::size_t inconsistent = 0;  // disagreeing with earlier fragments of the same frame
    std::size_t abandoned = 0;     // packets evicted incomplete
};

// A completed packet.
struct Reassembled {
    uint32_t frame = 0;
    int64_t pose_time_us = 0;
    std::span<const uint8_t> data;  // valid until the next call to add()
};

class Reassembler {
public:
    explicit Reassembler(const ReassemblerOptions& options = {});

    // Adds one parsed fragment. Returns true when it completed a packet (then `out` holds it).
    // Packets of frames not newer than the newest completed one are ignored. When a slot is
    // needed, the oldest incomplete packet is given up; its frame number goes to `abandoned`.
    bool add(const FragmentMessage& fragment, Reassembled& out, std::vector<uint32_t>& abandoned);
    // Gives up every incomplete packet older than `frame` (their numbers go to `abandoned`).
    void abandon_older_than(uint32_t frame, std::vector<uint32_t>& abandoned);

    const ReassemblyStats& stats() const { return stats_; }
    std::size_t bytes_held() const;  // memory held by the slots (bounded by the options)
    int64_t newest_completed() const { return newest_done_; }

private:
    struct Slot {
        bool used = false;
        uint32_t frame = 0;
        uint32_t total = 0;
        uint16_t count = 0;
        uint8_t group = 0;
        std::size_t payload = 0;  // bytes per data fragment (all but the last are full)
        int64_t pose_time_us = 0;
        std::vector<uint8_t> data;    // count * payload bytes
        std::vector<uint8_t> parity;  // groups * payload bytes
        std::vector<uint8_t> have;    // per data fragment
        std::vector<uint8_t> have_parity;
        std::size_t received = 0;
    };
    bool try_complete(Slot& slot);
    ReassemblerOptions options_;
    std::vector<Slot> slots_;
    int64_t newest_done_ = -1;
    ReassemblyStats stats_;
};

}  // namespace reprise::net
