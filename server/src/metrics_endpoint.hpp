#pragma once
// A tiny HTTP responder on 127.0.0.1 for Prometheus text metrics; polled, never blocks long.
#include <memory>
#include <string>

#include "reprise/core/status.hpp"

namespace reprise::server {

class MetricsEndpoint {
public:
    MetricsEndpoint();
    ~MetricsEndpoint();
    Status open(int port);  // 0: any free port
    int port() const;
    bool is_open() const;
    // Answers every connection waiting to be accepted with `body` (text/plain; version=0.0.4).
    void serve(const std::string& body);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace reprise::server
