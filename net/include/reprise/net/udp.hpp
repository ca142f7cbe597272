#pragma once
// A non-blocking IPv4 UDP socket (standalone Asio underneath) and address parsing.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "reprise/core/status.hpp"

namespace reprise::net {

struct Endpoint {
    uint32_t address = 0;  // IPv4, host byte order
    uint16_t port = 0;
    bool loopback() const { return (address >> 24) == 127; }
    bool operator==(const Endpoint&) const = default;
    std::string text() const;
};

// "A.B.C.D:PORT" or "localhost:PORT" (PORT 0 lets the system choose when binding).
Status parse_endpoint(const std::string& text, Endpoint& endpoint);

// Wakes a thread waiting in UdpSocket::wait_readable from another thread (an eventfd).
class Waker {
public:
    Waker();
    ~Waker();
    Waker(const Waker&) = delete;
    Waker& operator=(const Waker&) = delete;
    void wake();   // any thread
    void clear();  // the waiting thread, after it woke
    int fd() const { return fd_; }

private:
    int fd_ = -1;
};

class UdpSocket {
public:
    UdpSocket();
    ~UdpSocket();
    UdpSocket(UdpSocket&&) noexcept;
    UdpSocket& operator=(UdpSocket&&) noexcept;

    // Binds to `local` (port 0: any free port).
    Status bind(const Endpoint& local);
    Endpoint local() const;
    void close();
    bool is_open() const;

    // Sends one datagram; a full socket buffer or an unreachable peer drops it (UDP semantics).
    bool send_to(std::span<const uint8_t> datagram, const Endpoint& to);
    // Receives one datagram if one is waiting (datagrams longer than `capacity` are truncated
    // and flagged by a size of capacity + 1). False when none.
    bool receive(std::vector<uint8_t>& datagram, Endpoint& from, std::size_t capacity = 2048);
    // Waits until a datagram is readable, `waker` was woken or `timeout_us` passed.
    bool wait_readable(int64_t timeout_us, Waker* waker = nullptr);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Microseconds on the monotonic clock.
int64_t now_us();

}  // namespace reprise::net
