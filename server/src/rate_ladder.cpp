#include "reprise/server/rate_ladder.hpp"

#include <algorithm>

namespace reprise::server {

RateLadder::RateLadder(int aa_samples, double fps, bool aa_steps, const RateLadderOptions& options)
    : options_(options), hold_us_(options.hold_up_us) {
    levels_.push_back({aa_samples, fps});
    for (int aa = aa_samples / 2; aa_steps && aa >= 1; aa /= 2) levels_.push_back({aa, fps});
    const int aa = levels_.back().aa_samples;
    for (double f : {2.0 / 3.0, 1.0 / 2.0, 1.0 / 3.0, 1.0 / 4.0})
        if (fps * f >= 1.0) levels_.push_back({aa, fps * f});
}

void RateLadder::go(int level, int64_t now_us) {
    if (level > level_) {
        ++steps_down_;
        // An up step taken back soon: wait longer before the next try.
        if (last_up_us_ >= 0 && now_us - last_up_us_ < hold_us_ * 2)
            hold_us_ = std::min<int64_t>(hold_us_ * 2, 32'000'000);
    } else {
        ++steps_up_;
        last_up_us_ = now_us;
    }
    level_ = level;
    frames_ = 0;
    since_us_ = now_us;
}

bool RateLadder::update(double cost_ms, int64_t now_us) {
    if (since_us_ < 0) since_us_ = now_us;
    mean_ms_ = frames_ == 0 ? cost_ms
                            : (1.0 - options_.smoothing) * mean_ms_ + options_.smoothing * cost_ms;
    ++frames_;
    if (frames_ < options_.frames_to_judge) return false;
    const double period_ms = 1000.0 / current().fps;
    if (mean_ms_ > options_.down_at * period_ms && level_ + 1 < levels()) {
        go(level_ + 1, now_us);
        return true;
    }
    if (level_ > 0 && now_us - since_us_ >= hold_us_) {
        const RateLevel& up = levels_[std::size_t(level_ - 1)];
        // Rendering cost grows about with the anti-aliasing samples; a rate step keeps it.
        const double predicted = mean_ms_ * double(up.aa_samples) / double(current().aa_samples);
        if (predicted < options_.up_below * 1000.0 / up.fps) {
            go(level_ - 1, now_us);
            return true;
        }
    }
    return false;
}

}  // namespace reprise::server
