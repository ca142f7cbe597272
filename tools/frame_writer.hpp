#pragma once
// Writes frames as EXR on a thread of its own, so that a display loop never waits for the disk:
// submit() copies the frame into a free slot and returns; when every slot waits to be written
// the frame is dropped and counted (the display rate wins over the file count).
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "reprise/core/frame.hpp"
#include "reprise/core/status.hpp"

namespace reprise::cli {

class FrameWriter {
public:
    using WriteFunction = std::function<Status(const std::string& path, const Frame& frame)>;
    // Frame `index` goes to frame_path(folder, index); `slots` frames may wait at once.
    explicit FrameWriter(std::string folder, std::size_t slots = 8, WriteFunction write = {});
    ~FrameWriter();  // finish()

    // Written with its camera time and frame rate set to `time` and `fps` (a displayed frame's
    // instant). False when it was dropped (all slots waiting) or a write failed before.
    bool submit(const GBufferView& frame, int index, double time, double fps);
    // Writes what waits, stops the thread; the first write error, if any.
    Status finish();
    std::size_t written() const;
    std::size_t dropped() const;

private:
    void loop();
    struct Job {
        Frame frame;
        int index = 0;
    };
    std::string folder_;
    WriteFunction write_;
    mutable std::mutex mutex_;
    std::condition_variable ready_;
    std::deque<Job> queue_;
    std::vector<Job> free_;  // slots with their buffers, reused
    std::size_t written_ = 0, dropped_ = 0;
    bool stop_ = false;
    Status error_;
    std::thread thread_;
};

}  // namespace reprise::cli
