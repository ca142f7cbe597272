#include "frame_writer.hpp"

#include "reprise/core/exr.hpp"

namespace reprise::cli {

FrameWriter::FrameWriter(std::string folder, std::size_t slots, WriteFunction write)
    : folder_(std::move(folder)), write_(std::move(write)), free_(std::max<std::size_t>(1, slots)) {
    if (!write_)
        write_ = [](const std::string& path, const Frame& f) { return write_frame(path, f); };
    thread_ = std::thread([this] { loop(); });
}

FrameWriter::~FrameWriter() { (void)finish(); }

bool FrameWriter::submit(const GBufferView& frame, int index, double time, double fps) {
    Job job;
    {
        std::lock_guard lock(mutex_);
        if (!error_.ok() || stop_) return false;
        if (free_.empty()) {
            ++dropped_;
            return false;
        }
        job = std::move(free_.back());
        free_.pop_back();
    }
    job.frame.assign(frame);  // the copy outside the lock; the slot's buffers are reused
    job.frame.camera.time = time;
    job.frame.fps = fps;
    job.index = index;
    {
        std::lock_guard lock(mutex_);
        queue_.push_back(std::move(job));
    }
    ready_.notify_one();
    return true;
}

void FrameWriter::loop() {
    std::unique_lock lock(mutex_);
    for (;;) {
        ready_.wait(lock, [&] { return stop_ || !queue_.empty(); });
        if (queue_.empty()) return;  // stopped and nothing waits
        Job job = std::move(queue_.front());
        queue_.pop_front();
        lock.unlock();
        Status s = write_(frame_path(folder_, job.index), job.frame);
        lock.lock();
        if (s.ok())
            ++written_;
        else if (error_.ok())
            error_ = s;
        free_.push_back(std::move(job));
    }
}

Status FrameWriter::finish() {
    {
        std::lock_guard lock(mutex_);
        stop_ = true;
    }
    ready_.notify_one();
    if (thread_.joinable()) thread_.join();
    std::lock_guard lock(mutex_);
    return error_;
}

std::size_t FrameWriter::written() const {
    std::lock_guard lock(mutex_);
    return written_;
}

std::size_t FrameWriter::dropped() const {
    std::lock_guard lock(mutex_);
    return dropped_;
}

}  // namespace reprise::cli
