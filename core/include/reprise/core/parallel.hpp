#pragma once
// Row-parallel loops on a process-wide pool of worker threads (one per hardware thread).
#include <memory>
#include <type_traits>

namespace reprise {

// A non-owning reference to a callable `void(int, int)`: no copy, no allocation. It must not
// outlive the callable it refers to.
class RangeBody {
public:
    template <class F>
    requires(!std::is_same_v<std::remove_cvref_t<F>, RangeBody>)
        RangeBody(F& body)  // NOLINT: implicit on purpose
        : object_(const_cast<void*>(static_cast<const void*>(std::addressof(body)))),
          call_([](void* object, int a, int b) { (*static_cast<F*>(object))(a, b); }) {}
    void operator()(int a, int b) const { call_(object_, a, b); }

private:
    void* object_;
    void (*call_)(void*, int, int);
};

// Calls body(begin, end) on disjoint sub-ranges covering [begin, end), in parallel, and returns
// when all are done. Ranges shorter than `grain` run on the calling thread. Allocates nothing.
void parallel_for_ref(int begin, int end, RangeBody body, int grain = 16);

template <class F>
void parallel_for(int begin, int end, F&& body, int grain = 16) {
    parallel_for_ref(begin, end, RangeBody(body), grain);
}

// Number of threads parallel_for uses (REPRISE_THREADS overrides the hardware count).
int thread_count();

}  // namespace reprise
