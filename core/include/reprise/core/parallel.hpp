#pragma once
// Row-parallel loops on a process-wide pool of worker threads (one per hardware thread).
#include <cstddef>
#include <functional>

namespace reprise {

// Calls body(begin, end) on disjoint sub-ranges covering [begin, end), in parallel, and returns
// when all are done. Ranges shorter than `grain` run on the calling thread.
void parallel_for(int begin, int end, const std::function<void(int, int)>& body, int grain = 16);

// Number of threads parallel_for uses (REPRISE_THREADS overrides the hardware count).
int thread_count();

}  // namespace reprise
