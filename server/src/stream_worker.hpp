#pragma once
// The server's render worker (private to server/src): at the current rate of its RateLadder it
// renders and encodes one frame per started session and hands it to the network thread.
#include <atomic>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "reprise/server/stream_server.hpp"
#include "stream_session.hpp"

namespace reprise::server::detail {

// What the worker shares with the network thread.
struct WorkerLink {
    const StreamServerOptions& options;
    std::mutex& sessions_mutex;  // guards `sessions` (written by the network thread only)
    const std::vector<std::shared_ptr<Session>>& sessions;
    std::mutex& stats_mutex;
    StreamServerStats& stats;
    net::Waker& waker;  // woken when a frame was handed over or the worker failed
};

class RenderWorker {
public:
    explicit RenderWorker(WorkerLink link);
    ~RenderWorker();  // stops and joins
    void start();
    void stop();
    bool failed() const { return failed_.load(); }
    Status status() const;  // why it failed

private:
    void loop();
    void warm_up();
    // The scene of that name, loaded once and kept while a session shows it (and the default).
    Status scene(const std::string& name, std::shared_ptr<const LoadedScene>& out);
    double produce(Session& s, int64_t now);  // render + encode ms, 0 when nothing was rendered
    Status render_encode(Session& s, const net::PoseMessage& pose, double& render_ms,
                         double& encode_ms);
    void hand_over(Session& s, std::span<const uint8_t> payload, int64_t pose_time_us);
    bool sleep_until(int64_t when_us);  // false when stopped
    void publish_level();

    WorkerLink link_;
    RateLadder ladder_;
    std::unique_ptr<Renderer> renderer_;
    std::vector<std::shared_ptr<Session>> snapshot_;
    std::map<std::string, std::shared_ptr<const LoadedScene>> scenes_;
    std::thread thread_;
    mutable std::mutex mutex_;  // for stop_ and failure_
    std::condition_variable wake_;
    bool stop_ = false;
    Status failure_;
    std::atomic<bool> failed_{false};
};

}  // namespace reprise::server::detail
