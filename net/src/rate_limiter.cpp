#include "reprise/net/rate_limiter.hpp"

#include <algorithm>

namespace reprise::net {

HandshakeRateLimiter::HandshakeRateLimiter(const RateLimitOptions& options) : options_(options) {
    global_.tokens = options_.burst;
    global_.updated_us = -1;
    sources_.reserve(options_.sources);
}

void HandshakeRateLimiter::refill(Bucket& b, double rate, double burst, int64_t now_us) {
    if (b.updated_us >= 0 && now_us > b.updated_us)
        b.tokens = std::min(burst, b.tokens + rate * (now_us - b.updated_us) * 1e-6);
    b.updated_us = now_us;
}

HandshakeRateLimiter::Bucket& HandshakeRateLimiter::source(uint32_t address, int64_t now_us) {
    for (Bucket& b : sources_)
        if (b.address == address) return b;
    if (sources_.size() < std::max<std::size_t>(1, options_.sources)) {
        sources_.push_back({address, options_.per_source_burst, now_us});
        return sources_.back();
    }
    Bucket& oldest = *std::min_element(
        sources_.begin(), sources_.end(),
        [](const Bucket& a, const Bucket& b) { return a.updated_us < b.updated_us; });
    oldest = {address, options_.per_source_burst, now_us};
    return oldest;
}

bool HandshakeRateLimiter::allow(uint32_t address, int64_t now_us) {
    refill(global_, options_.per_second, options_.burst, now_us);
    Bucket& s = source(address, now_us);
    refill(s, options_.per_source_per_second, options_.per_source_burst, now_us);
    if (global_.tokens < 1.0 || s.tokens < 1.0) {
        ++refused_;
        return false;
    }
    global_.tokens -= 1.0;
    s.tokens -= 1.0;
    return true;
}

bool HandshakeRateLimiter::allow_source(uint32_t address, int64_t now_us) {
    Bucket& s = source(address, now_us);
    refill(s, options_.per_source_per_second, options_.per_source_burst, now_us);
    if (s.tokens < 1.0) {
        ++refused_;
        return false;
    }
    s.tokens -= 1.0;
    return true;
}

void HandshakeRateLimiter::penalise(uint32_t address, int64_t now_us) {
    Bucket& s = source(address, now_us);
    refill(s, options_.per_source_per_second, options_.per_source_burst, now_us);
    s.tokens = std::min(s.tokens, 0.0);
}

}  // namespace reprise::net
