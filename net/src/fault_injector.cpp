#include "reprise/net/fault_injector.hpp"

#include <algorithm>

namespace reprise::net {

namespace {
bool later(const auto& a, const auto& b) {
    return a.due_us != b.due_us ? a.due_us > b.due_us : a.order > b.order;
}
}  // namespace

FaultInjector::FaultInjector(const FaultOptions& options)
    : options_(options), state_(options.seed) {}

double FaultInjector::uniform() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return double(z >> 11) * (1.0 / 9007199254740992.0);
}

void FaultInjector::submit(std::span<const uint8_t> datagram, int64_t now_us) {
    ++stats_.submitted;
    // Every random draw happens for every datagram, so one option never shifts another's sequence.
    const double u_loss = uniform(), u_burst = uniform(), u_jitter = uniform(),
                 u_reorder = uniform();
    if (bad_) {
        if (u_burst < options_.burst_end) bad_ = false;
    } else if (u_burst < options_.burst_start) {
        bad_ = true;
    }
    if (bad_) {
        ++stats_.lost_burst;
        return;
    }
    if (u_loss < options_.loss) {
        ++stats_.lost_random;
        return;
    }
    int64_t leave_us = now_us;
    if (options_.bandwidth_kbps > 0.0) {
        // Bytes still queued at the bottleneck are those not yet serialised.
        const int64_t backlog_us = std::max<int64_t>(0, link_free_us_ - now_us);
        const double bytes_queued = backlog_us * options_.bandwidth_kbps / 8000.0;
        if (bytes_queued + datagram.size() > double(options_.queue_bytes)) {
            ++stats_.lost_queue;
            return;
        }
        const int64_t serialise_us = int64_t(datagram.size() * 8000.0 / options_.bandwidth_kbps);
        link_free_us_ = std::max(link_free_us_, now_us) + serialise_us;
        leave_us = link_free_us_;
    }
    double extra_ms = options_.delay_ms + u_jitter * options_.jitter_ms;
    if (u_reorder < options_.reorder) {
        extra_ms += options_.reorder_ms;
        ++stats_.reordered;
    }
    InFlight f{leave_us + int64_t(extra_ms * 1000.0), order_++, {}};
    if (!spare_.empty()) {
        f.data = std::move(spare_.back());
        spare_.pop_back();
    }
    f.data.assign(datagram.begin(), datagram.end());
    flight_.push_back(std::move(f));
    std::push_heap(flight_.begin(), flight_.end(),
                   [](const InFlight& a, const InFlight& b) { return later(a, b); });
}

bool FaultInjector::deliver(int64_t now_us, std::vector<uint8_t>& datagram) {
    if (flight_.empty() || flight_.front().due_us > now_us) return false;
    std::pop_heap(flight_.begin(), flight_.end(),
                  [](const InFlight& a, const InFlight& b) { return later(a, b); });
    std::swap(datagram, flight_.back().data);
    spare_.push_back(std::move(flight_.back().data));
    flight_.pop_back();
    ++stats_.delivered;
    return true;
}

int64_t FaultInjector::next_due(int64_t now_us) const {
    if (flight_.empty()) return -1;
    return std::max<int64_t>(0, flight_.front().due_us - now_us);
}

}  // namespace reprise::net
