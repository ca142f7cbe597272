#pragma once
// An in-process network between two endpoints: datagrams go in with the time they were sent and
// come out when the simulated link delivers them (or never). Seeded: the same seed and the same
// sequence of calls give the same losses, delays and order on every machine.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace reprise::net {

struct FaultOptions {
    double loss = 0.0;  // independent loss probability per datagram
    // Burst loss (Gilbert-Elliott): the link turns bad with burst_start per datagram, stays bad
    // with probability 1 - burst_end, and loses every datagram while bad.
    double burst_start = 0.0;
    double burst_end = 0.25;
    double delay_ms = 0.0;   // one-way delay
    double jitter_ms = 0.0;  // uniform extra delay in [0, jitter_ms] (reorders)
    double reorder = 0.0;    // probability that a datagram is held back by reorder_ms more
    double reorder_ms = 5.0;
    double bandwidth_kbps = 0.0;           // 0 = unlimited; else serialised at this rate
    std::size_t queue_bytes = 256 * 1024;  // bottleneck queue; tail drop beyond it
    uint64_t seed = 1;
};

struct FaultStats {
    std::size_t submitted = 0, delivered = 0, lost_random = 0, lost_burst = 0, lost_queue = 0,
                reordered = 0;
};

class FaultInjector {
public:
    explicit FaultInjector(const FaultOptions& options = {});

    // One datagram enters the link at `now_us` (microseconds on any monotonic clock).
    void submit(std::span<const uint8_t> datagram, int64_t now_us);
    // The next datagram due by `now_us`, in delivery order; false when none is due.
    bool deliver(int64_t now_us, std::vector<uint8_t>& datagram);
    // Microseconds until the next delivery (-1 when nothing is in flight).
    int64_t next_due(int64_t now_us) const;

    const FaultStats& stats() const { return stats_; }
    std::size_t in_flight() const { return flight_.size(); }

private:
    double uniform();  // [0, 1) from splitmix64: the same on every platform
    struct InFlight {
        int64_t due_us;
        uint64_t order;
        std::vector<uint8_t> data;
    };
    FaultOptions options_;
    uint64_t state_;
    bool bad_ = false;
    int64_t link_free_us_ = 0;
    std::size_t queued_bytes_ = 0;
    uint64_t order_ = 0;
    std::vector<InFlight> flight_;  // a min-heap on (due, order)
    std::vector<std::vector<uint8_t>> spare_;
    FaultStats stats_;
};

}  // namespace reprise::net
