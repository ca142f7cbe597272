#include "reprise/core/simd.hpp"

#include <hwy/targets.h>

namespace reprise::simd {

std::vector<Target> available_targets() {
    std::vector<Target> out;
    for (const int64_t bits : hwy::SupportedAndGeneratedTargets())
        out.push_back({.bits = bits, .name = hwy::TargetName(bits)});
    return out;  // Highway lists lower bits first, and lower bits are the better targets
}

void force_target(int64_t bits) { hwy::SetSupportedTargetsForTest(bits); }

Target current_target() {
    const std::vector<Target> targets = available_targets();
    return targets.empty() ? Target{} : targets.front();
}

}  // namespace reprise::simd
