// checkasm-style: every (kernel, reference) pair of the registry, at every SIMD level this CPU
// runs, on random and worst-case inputs of awkward sizes, gives what its reference gives.
#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "kernel_case.hpp"
#include "reprise/core/simd.hpp"

namespace reprise::kernels {
namespace {

const std::vector<std::pair<int, int>> kSizes = {{1, 1},  {1, 7},  {3, 2},    {7, 5},  {17, 3},
                                                 {33, 4}, {67, 9}, {130, 33}, {257, 6}};

struct RestoreTarget {
    ~RestoreTarget() { simd::force_target(0); }
};

// Highway compiles a vector level and its portable fallback at least; on x86-64 the build has
// SSE2 through AVX-512 and a machine runs two or more of them.
TEST(Kernels, SeveralSimdLevelsAreAvailable) {
    const std::vector<simd::Target> targets = simd::available_targets();
    ASSERT_GE(targets.size(), 2u);
    for (const simd::Target& t : targets) EXPECT_NE(t.bits, 0);
    RestoreTarget restore;
    simd::force_target(targets.back().bits);
    EXPECT_EQ(simd::current_target().bits, targets.back().bits);
    simd::force_target(0);
    EXPECT_EQ(simd::current_target().bits, targets.front().bits);
}

TEST(Kernels, EveryLevelAgreesWithTheReference) {
    RestoreTarget restore;
    const std::vector<simd::Target> targets = simd::available_targets();
    ASSERT_GE(warp_kernels().size(), 9u);
    ASSERT_GE(codec_kernels().size(), 10u);
    for (const KernelEntry& entry : every_kernel()) {
        std::unique_ptr<KernelCase> k = entry.make();
        uint32_t seed = 1;
        for (const KernelInputs inputs : {KernelInputs::Random, KernelInputs::WorstCase})
            for (const auto& [w, h] : kSizes) {
                k->generate(w, h, inputs, seed++);
                k->reset_reference();
                k->run_reference();
                for (const simd::Target& target : targets) {
                    simd::force_target(target.bits);
                    k->reset();
                    k->run();
                    const std::string difference = k->compare();
                    EXPECT_TRUE(difference.empty())
                        << entry.name << " at " << target.name << ", " << w << "x" << h
                        << (inputs == KernelInputs::Random ? " random" : " worst case") << ": "
                        << difference;
                    if (!entry.dispatched) break;  // one vector path, chosen when compiled
                }
                simd::force_target(0);
            }
    }
}

}  // namespace
}  // namespace reprise::kernels
