#include "reprise/net/udp.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <asio/io_context.hpp>
#include <asio/ip/udp.hpp>
#include <charconv>
#include <chrono>

namespace reprise::net {

std::string Endpoint::text() const {
    return std::to_string(address >> 24) + "." + std::to_string((address >> 16) & 255) + "." +
           std::to_string((address >> 8) & 255) + "." + std::to_string(address & 255) + ":" +
           std::to_string(port);
}

Status parse_endpoint(const std::string& text, Endpoint& endpoint) {
    const auto colon = text.rfind(':');
    if (colon == std::string::npos)
        return Status::error("address '" + text + "': expected HOST:PORT");
    std::string host = text.substr(0, colon), port = text.substr(colon + 1);
    if (host == "localhost") host = "127.0.0.1";
    asio::error_code ec;
    const asio::ip::address_v4 a = asio::ip::make_address_v4(host, ec);
    if (ec)
        return Status::error("address '" + text + "': host must be an IPv4 address or localhost");
    unsigned value = 0;
    auto [end, err] = std::from_chars(port.data(), port.data() + port.size(), value);
    if (port.empty() || err != std::errc() || end != port.data() + port.size() || value > 65535)
        return Status::error("address '" + text + "': port must be 0..65535");
    endpoint.address = a.to_uint();
    endpoint.port = uint16_t(value);
    return {};
}

struct UdpSocket::Impl {
    asio::io_context io;
    asio::ip::udp::socket socket{io};
};

namespace {
asio::ip::udp::endpoint to_asio(const Endpoint& e) {
    return {asio::ip::address_v4(e.address), e.port};
}
}  // namespace

UdpSocket::UdpSocket() : impl_(std::make_unique<Impl>()) {}
UdpSocket::~UdpSocket() = default;
UdpSocket::UdpSocket(UdpSocket&&) noexcept = default;
UdpSocket& UdpSocket::operator=(UdpSocket&&) noexcept = default;

Status UdpSocket::bind(const Endpoint& local) {
    asio::error_code ec;
    impl_->socket.close(ec);
    impl_->socket.open(asio::ip::udp::v4(), ec);
    if (!ec) impl_->socket.bind(to_asio(local), ec);
    if (!ec) impl_->socket.non_blocking(true, ec);
    if (!ec) impl_->socket.set_option(asio::socket_base::receive_buffer_size(1 << 20), ec);
    if (ec) return Status::error("udp " + local.text() + ": " + ec.message());
    return {};
}

Endpoint UdpSocket::local() const {
    asio::error_code ec;
    auto e = impl_->socket.local_endpoint(ec);
    if (ec) return {};
    return {e.address().to_v4().to_uint(), e.port()};
}

void UdpSocket::close() {
    asio::error_code ec;
    impl_->socket.close(ec);
}

bool UdpSocket::is_open() const { return impl_->socket.is_open(); }

bool UdpSocket::send_to(std::span<const uint8_t> datagram, const Endpoint& to) {
    asio::error_code ec;
    impl_->socket.send_to(asio::buffer(datagram.data(), datagram.size()), to_asio(to), 0, ec);
    return !ec;
}

bool UdpSocket::receive(std::vector<uint8_t>& datagram, Endpoint& from, std::size_t capacity) {
    if (!impl_->socket.is_open()) return false;
    datagram.resize(capacity + 1);
    asio::ip::udp::endpoint sender;
    asio::error_code ec;
    for (;;) {
        const std::size_t n = impl_->socket.receive_from(
            asio::buffer(datagram.data(), datagram.size()), sender, 0, ec);
        if (ec == asio::error::connection_refused) continue;  // ICMP from an earlier send
        if (ec) return false;
        datagram.resize(n);
        if (!sender.address().is_v4()) continue;
        from = {sender.address().to_v4().to_uint(), sender.port()};
        return true;
    }
}

bool UdpSocket::wait_readable(int64_t timeout_us, Waker* waker) {
    if (!impl_->socket.is_open()) return false;
    pollfd p[2] = {{.fd = impl_->socket.native_handle(), .events = POLLIN, .revents = 0},
                   {.fd = waker ? waker->fd() : -1, .events = POLLIN, .revents = 0}};
    const int ms = int(std::clamp<int64_t>((timeout_us + 999) / 1000, 0, 1000));
    const bool ready = ::poll(p, waker ? 2 : 1, ms) > 0;
    if (waker && (p[1].revents & POLLIN)) waker->clear();
    return ready && (p[0].revents & POLLIN);
}

Waker::Waker() : fd_(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {}
Waker::~Waker() {
    if (fd_ >= 0) ::close(fd_);
}
void Waker::wake() {
    const uint64_t one = 1;
    (void)!::write(fd_, &one, sizeof one);
}
void Waker::clear() {
    uint64_t value;
    (void)!::read(fd_, &value, sizeof value);
}

int64_t now_us() {
    return std::chrono::duration_cast<std::chrono::microseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

}  // namespace reprise::net
