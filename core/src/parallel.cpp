#include "reprise/core/parallel.hpp"

#include <algorithm>
#include <cstdint>
#include <condition_variable>
#include <cstdlib>
#include <mutex>
#include <thread>
#include <vector>

namespace reprise {

namespace {

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

    // Runs task(i) for i in [0, count); the caller takes part.
    void run(int count, const std::function<void(int)>& task) {
        std::lock_guard one_caller_at_a_time(busy_);
        std::unique_lock lock(mutex_);
        task_ = &task;
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
            const std::function<void(int)>* task = task_;
            lock.unlock();
            (*task)(i);
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
    const std::function<void(int)>* task_ = nullptr;
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

void parallel_for(int begin, int end, const std::function<void(int, int)>& body, int grain) {
    const int n = end - begin;
    if (n <= 0) return;
    const int threads = inside_parallel ? 1 : thread_count();
    if (threads == 1 || n <= std::max(grain, 1)) {
        body(begin, end);
        return;
    }
    const int chunks = std::min(n / std::max(grain, 1), threads * 4);
    std::function<void(int)> task = [&](int c) {
        inside_parallel = true;
        int a = begin + int(std::int64_t(n) * c / chunks), b = begin + int(std::int64_t(n) * (c + 1) / chunks);
        body(a, b);
        inside_parallel = false;
    };
    pool().run(chunks, task);
}

}  // namespace reprise
