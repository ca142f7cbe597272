#include "reprise/net/guess_budget.hpp"

#include <algorithm>

namespace reprise::net {

GuessBudget::GuessBudget(const GuessBudgetOptions& options)
    : options_(options), tokens_(options.burst), interval_s_(options.first_interval_s) {}

void GuessBudget::refill(int64_t now_us) {
    if (updated_us_ >= 0 && now_us > updated_us_)
        tokens_ =
            std::min(options_.burst, tokens_ + double(now_us - updated_us_) * 1e-6 / interval_s_);
    if (now_us > updated_us_) updated_us_ = now_us;
}

bool GuessBudget::available(int64_t now_us) {
    refill(now_us);
    return tokens_ >= 1.0;
}

bool GuessBudget::start(int64_t now_us) {
    if (!available(now_us)) return false;
    tokens_ -= 1.0;
    interval_s_ = std::min(options_.longest_interval_s, interval_s_ * 2.0);
    return true;
}

void GuessBudget::confirmed(int64_t now_us) {
    refill(now_us);
    tokens_ = std::min(options_.burst, tokens_ + 1.0);
    interval_s_ = options_.first_interval_s;
}

}  // namespace reprise::net
