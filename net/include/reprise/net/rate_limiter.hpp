#pragma once
// Token buckets for handshakes: one for all sources and one per source address, in a table of
// bounded size (the least recently seen address is forgotten first).
#include <cstddef>
#include <cstdint>
#include <vector>

namespace reprise::net {

struct RateLimitOptions {
    double per_second = 20.0;  // all sources together
    double burst = 20.0;
    double per_source_per_second = 2.0;
    double per_source_burst = 5.0;
    std::size_t sources = 256;  // addresses remembered
};

class HandshakeRateLimiter {
public:
    explicit HandshakeRateLimiter(const RateLimitOptions& options = {});
    // Takes one token from the global bucket and the source's bucket; false when either is empty.
    bool allow(uint32_t address, int64_t now_us);
    // The source's bucket only (a repeated hello answered from memory costs no new work).
    bool allow_source(uint32_t address, int64_t now_us);
    // A failed key confirmation costs the source its whole bucket.
    void penalise(uint32_t address, int64_t now_us);
    std::size_t refused() const { return refused_; }

private:
    struct Bucket {
        uint32_t address = 0;
        double tokens = 0.0;
        int64_t updated_us = 0;
    };
    Bucket& source(uint32_t address, int64_t now_us);
    static void refill(Bucket& b, double rate, double burst, int64_t now_us);
    RateLimitOptions options_;
    Bucket global_;
    std::vector<Bucket> sources_;
    std::size_t refused_ = 0;
};

}  // namespace reprise::net
