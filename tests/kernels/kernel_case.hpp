#pragma once
// The checkasm-style kernel harness: every optimized kernel of the libraries (their row kernels,
// declared beside their scalar references in warp/src/kernels.hpp and codec/src/kernels.hpp) as a
// case that generates random and worst-case inputs, runs the reference and the kernel, and
// compares. tests/test_kernels.cpp checks every SIMD level against the reference;
// `reprise bench kernels` times them.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace reprise::kernels {

enum class KernelInputs {
    Random,     // a plausible frame
    WorstCase,  // NaN/Inf depth and motion, huge motion, points behind the camera, signed zeros
};

// One (kernel, reference) pair on inputs it generates and owns.
class KernelCase {
public:
    virtual ~KernelCase() = default;
    virtual void generate(int width, int height, KernelInputs inputs, uint32_t seed) = 0;
    // Put back what the kernel (reset) or the reference (reset_reference) changes in place: call
    // before each run (benchmarks leave it out of the time).
    virtual void reset() {}
    virtual void reset_reference() {}
    virtual void run_reference() = 0;  // the scalar reference, into its own outputs
    virtual void run() = 0;            // the optimized kernel (at the current SIMD level)
    // Empty when the two outputs agree as the kernel promises, else the first difference.
    [[nodiscard]] virtual std::string compare() const = 0;
};

struct KernelEntry {
    const char* name;
    const char* promise;  // "bit-exact" or the tolerance
    // True when the SIMD level is chosen at run time (simd::force_target applies); false for a
    // kernel whose vector code is fixed when it is compiled.
    bool dispatched;
    std::unique_ptr<KernelCase> (*make)();
};

std::span<const KernelEntry> warp_kernels();
std::span<const KernelEntry> codec_kernels();

inline std::vector<KernelEntry> every_kernel() {
    std::vector<KernelEntry> entries(warp_kernels().begin(), warp_kernels().end());
    entries.insert(entries.end(), codec_kernels().begin(), codec_kernels().end());
    return entries;
}

}  // namespace reprise::kernels
