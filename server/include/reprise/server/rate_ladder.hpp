#pragma once
// Keeping a server's frame rate: when rendering and encoding a frame takes longer than the frame
// period, step down a ladder (fewer anti-aliasing samples first, then a lower frame rate); step
// back up when the cost measured at a level leaves room for the level above (with hysteresis).
#include <cstdint>
#include <vector>

namespace reprise::server {

struct RateLevel {
    int aa_samples = 1;
    double fps = 30.0;
};

struct RateLadderOptions {
    double down_at = 0.95;    // step down when the mean cost exceeds this × the period
    double up_below = 0.7;    // step up when the cost predicted above is below this × its period
    int frames_to_judge = 3;  // frames measured at a level before it is judged
    int64_t hold_up_us = 2'000'000;  // time at a level before stepping up; doubles when an up
                                     // step had to be taken back, at most 32 s
    double smoothing = 0.3;          // weight of the newest cost in the running mean
};

class RateLadder {
public:
    // Level 0 is what was asked for; each AA level halves the samples (only with `aa_steps`),
    // then the rate goes to 2/3, 1/2, 1/3 and 1/4 of it (not below 1 Hz).
    RateLadder(int aa_samples, double fps, bool aa_steps, const RateLadderOptions& options = {});

    // The cost (ms) of one frame tick rendered at the current level; true when the level changed.
    bool update(double cost_ms, int64_t now_us);

    int level() const { return level_; }
    int levels() const { return int(levels_.size()); }
    const RateLevel& current() const { return levels_[std::size_t(level_)]; }
    double mean_cost_ms() const { return mean_ms_; }
    int steps_down() const { return steps_down_; }
    int steps_up() const { return steps_up_; }

private:
    void go(int level, int64_t now_us);
    RateLadderOptions options_;
    std::vector<RateLevel> levels_;
    int level_ = 0;
    double mean_ms_ = 0.0;
    int frames_ = 0;
    int64_t since_us_ = -1, last_up_us_ = -1;
    int64_t hold_us_;
    int steps_down_ = 0, steps_up_ = 0;
};

}  // namespace reprise::server
