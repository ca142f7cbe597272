#include "reprise/core/parallel.hpp"

#include <algorithm>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <thread>
#include <vector>

namespace reprise {

namespace {

using Task = void (*)(const void* context, int index);

class Pool {
public:
    explicit Pool(int threads) {
        for (int i = 1; i < threads; ++i) workers_.emplace_back([this] { work(); });
    }
    ~Pool() {
        {
            std::lock_guard lock(mutex_);
            stop_ = true;
        }
        wake_.notify_all();
        for (std::thread& t : workers_) t.join();
    }
    int size() const { return int(workers_.size()) + 1; }

    // Runs task(context, i) for i in [0, count); the caller takes part.
    void run(int count, Task task, const void* context) {
        std::lock_guard one_caller_at_a_time(busy_);
        std::unique_lock lock(mutex_);
        task_ = task;
        context_ = context;
        count_ = count;
        next_ = 0;
        pending_ = count;
        ++generation_;
        wake_.notify_all();
        drain(lock);
        done_.wait(lock, [&] { return pending_ == 0; });
        task_ = nullptr;
    }

private:
    void drain(std::unique_lock<std::mutex>& lock) {
        while (task_ && next_ < count_) {
            int i = next_++;
            const Task task = task_;
            const void* context = context_;
            lock.unlock();
            task(context, i);
            lock.lock();
            if (--pending_ == 0) done_.notify_all();
        }
    }
    void work() {
        std::unique_lock lock(mutex_);
        unsigned long seen = 0;
        while (true) {
            wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
            if (stop_) return;
            seen = generation_;
            drain(lock);
        }
    }

    std::vector<std::thread> workers_;
    std::mutex busy_, mutex_;
    std::condition_variable wake_, done_;
    Task task_ = nullptr;
    const void* context_ = nullptr;
    int count_ = 0, next_ = 0, pending_ = 0;
    unsigned long generation_ = 0;
    bool stop_ = false;
};

int configured_threads() {
    if (const char* env = std::getenv("REPRISE_THREADS")) {
        int n = std::atoi(env);
        if (n >= 1 && n <= 256) return n;
    }
    return std::max(1u, std::thread::hardware_concurrency());
}

Pool& pool() {
    static Pool instance(configured_threads());
    return instance;
}

// Nested calls (a body that itself calls parallel_for) run serially.
thread_local bool inside_parallel = false;

}  // namespace

int thread_count() { return pool().size(); }

void parallel_for_ref(int begin, int end, RangeBody body, int grain) {
    const int n = end - begin;
    if (n <= 0) return;
    const int threads = inside_parallel ? 1 : thread_count();
    if (threads == 1 || n <= std::max(grain, 1)) {
        body(begin, end);
        return;
    }
    struct Split {
        int begin, n, chunks;
        RangeBody body;
    };
    const Split split{begin, n, std::min(n / std::max(grain, 1), threads * 4), body};
    pool().run(
        split.chunks,
        [](const void* context, int c) {
            const Split& s = *static_cast<const Split*>(context);
            inside_parallel = true;
            const int a = s.begin + int(std::int64_t(s.n) * c / s.chunks);
            const int b = s.begin + int(std::int64_t(s.n) * (c + 1) / s.chunks);
            s.body(a, b);
            inside_parallel = false;
        },
        &split);
}

}  // namespace reprise
