#pragma once
// The PIN's guessing budget, shared by every source address: a token bucket over handshakes that
// start with the PIN. A handshake costs a token when it starts and counts as a failure at once
// (abandoning it after reading the ServerHello saves the guesser nothing); only a valid key
// confirmation gives the token back. Every unconfirmed start doubles the refill interval, up to
// a cap; a confirmation resets it. Figures: docs/protocol.md, "PIN guessing".
#include <cstdint>

namespace reprise::net {

struct GuessBudgetOptions {
    double burst = 4.0;                // guesses after a quiet period
    double first_interval_s = 1.0;     // one more token this often with no unconfirmed start
    double longest_interval_s = 30.0;  // the back-off's cap: 120 guesses an hour
};

class GuessBudget {
public:
    explicit GuessBudget(const GuessBudgetOptions& options = {});
    // Whether a token is there (takes nothing).
    bool available(int64_t now_us);
    // Takes a token for a handshake that starts now; false when none is left.
    bool start(int64_t now_us);
    // The handshake proved the PIN: its token back and the back-off reset.
    void confirmed(int64_t now_us);
    double interval_s() const { return interval_s_; }

private:
    void refill(int64_t now_us);
    GuessBudgetOptions options_;
    double tokens_ = 0.0, interval_s_ = 0.0;
    int64_t updated_us_ = -1;
};

}  // namespace reprise::net
