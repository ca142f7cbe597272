#pragma once
// Timing for the benchmarks: milliseconds of repeated runs, best and median, and the lists
// benchmarks take on the command line.
#include <chrono>
#include <map>
#include <string>
#include <vector>

namespace reprise::cli {

using BenchClock = std::chrono::steady_clock;

double ms_since(BenchClock::time_point start);

// Milliseconds of repeated runs of one thing.
struct Timing {
    std::vector<double> ms;
    double best() const;    // NaN when empty
    double median() const;  // the upper median; NaN when empty
};

template <class F>
void time_once(Timing& timing, F&& run) {
    const auto start = BenchClock::now();
    run();
    timing.ms.push_back(ms_since(start));
}

// The fastest of `runs` (at least one) calls of `run`, in ms.
template <class F>
double best_of(int runs, F&& run) {
    Timing timing;
    for (int i = 0; i < (runs < 1 ? 1 : runs); ++i) time_once(timing, run);
    return timing.best();
}

// Per frame, the fastest time seen over repeated runs of a sequence.
void keep_fastest(std::map<int, double>& fastest, int frame, double ms);

// "a,b,,c" -> {"a", "b", "c"}.
std::vector<std::string> split_list(const std::string& list);

}  // namespace reprise::cli
