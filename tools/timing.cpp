#include "timing.hpp"

#include <algorithm>
#include <cmath>

namespace reprise::cli {

double ms_since(BenchClock::time_point start) {
    return std::chrono::duration<double, std::milli>(BenchClock::now() - start).count();
}

double Timing::best() const { return ms.empty() ? NAN : *std::min_element(ms.begin(), ms.end()); }

double Timing::median() const {
    if (ms.empty()) return NAN;
    std::vector<double> sorted = ms;
    std::sort(sorted.begin(), sorted.end());
    return sorted[sorted.size() / 2];
}

void keep_fastest(std::map<int, double>& fastest, int frame, double ms) {
    auto [it, inserted] = fastest.try_emplace(frame, ms);
    if (!inserted) it->second = std::min(it->second, ms);
}

std::vector<std::string> split_list(const std::string& list) {
    std::vector<std::string> items;
    std::size_t start = 0;
    while (start <= list.size()) {
        std::size_t end = std::min(list.find(',', start), list.size());
        if (end > start) items.push_back(list.substr(start, end - start));
        start = end + 1;
    }
    return items;
}

}  // namespace reprise::cli
