#pragma once
// The SIMD levels the kernels were compiled for and the CPU supports (Highway's runtime dispatch),
// and a switch that forces one of them (tests and `reprise bench kernels` run every level).
#include <cstdint>
#include <vector>

namespace reprise::simd {

struct Target {
    int64_t bits = 0;       // a Highway target bit (HWY_AVX2, HWY_SSE4, ...)
    const char* name = "";  // "AVX2", "SSE4", "EMU128" (Highway's portable scalar code), ...
};

// Best first.
std::vector<Target> available_targets();
// Every dispatched kernel uses `target` from now on (bits 0: the best the CPU supports again).
void force_target(int64_t bits);
// The level a dispatched kernel would run at now.
Target current_target();

}  // namespace reprise::simd
