#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

#include "reprise/core/parallel.hpp"

using reprise::parallel_for;

TEST(Parallel, CoversEveryIndexExactlyOnce) {
    for (int n : {0, 1, 7, 16, 17, 1000, 4321}) {
        std::vector<std::atomic<int>> hits(n);
        parallel_for(
            0, n,
            [&](int a, int b) {
                for (int i = a; i < b; ++i) hits[i]++;
            },
            1);
        for (int i = 0; i < n; ++i) ASSERT_EQ(hits[i].load(), 1) << n << " " << i;
    }
}

TEST(Parallel, NestedAndConcurrentCallsComplete) {
    std::atomic<long> total{0};
    std::vector<std::thread> callers;
    for (int t = 0; t < 3; ++t)
        callers.emplace_back([&] {
            parallel_for(
                0, 64,
                [&](int a, int b) {
                    for (int i = a; i < b; ++i)
                        parallel_for(
                            0, 100, [&](int c, int d) { total += d - c; }, 1);
                },
                1);
        });
    for (auto& c : callers) c.join();
    EXPECT_EQ(total.load(), 3L * 64 * 100);
}
