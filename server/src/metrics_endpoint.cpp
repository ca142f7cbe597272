#include "metrics_endpoint.hpp"

#include <asio/io_context.hpp>
#include <asio/ip/tcp.hpp>
#include <asio/read.hpp>
#include <asio/write.hpp>

namespace reprise::server {

struct MetricsEndpoint::Impl {
    asio::io_context io;
    asio::ip::tcp::acceptor acceptor{io};
};

MetricsEndpoint::MetricsEndpoint() : impl_(std::make_unique<Impl>()) {}
MetricsEndpoint::~MetricsEndpoint() = default;

Status MetricsEndpoint::open(int port) {
    if (port < 0 || port > 65535) return Status::error("metrics port must be 0..65535");
    asio::error_code ec;
    const asio::ip::tcp::endpoint at(asio::ip::address_v4::loopback(), uint16_t(port));
    impl_->acceptor.open(at.protocol(), ec);
    if (!ec) impl_->acceptor.set_option(asio::socket_base::reuse_address(true), ec);
    if (!ec) impl_->acceptor.bind(at, ec);
    if (!ec) impl_->acceptor.listen(8, ec);
    if (!ec) impl_->acceptor.non_blocking(true, ec);
    if (ec)
        return Status::error("metrics endpoint 127.0.0.1:" + std::to_string(port) + ": " +
                             ec.message());
    return {};
}

int MetricsEndpoint::port() const {
    asio::error_code ec;
    auto e = impl_->acceptor.local_endpoint(ec);
    return ec ? -1 : e.port();
}

bool MetricsEndpoint::is_open() const { return impl_->acceptor.is_open(); }

void MetricsEndpoint::serve(const std::string& body) {
    if (!impl_->acceptor.is_open()) return;
    for (int i = 0; i < 4; ++i) {
        asio::error_code ec;
        asio::ip::tcp::socket s(impl_->io);
        impl_->acceptor.accept(s, ec);
        if (ec) return;
        // The request is not read beyond what has arrived: any request gets the metrics.
        char request[1024];
        s.non_blocking(true, ec);
        s.read_some(asio::buffer(request), ec);
        s.non_blocking(false, ec);
        const std::string response =
            "HTTP/1.0 200 OK\r\nContent-Type: text/plain; version=0.0.4\r\nContent-Length: " +
            std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" + body;
        asio::write(s, asio::buffer(response), ec);
        s.shutdown(asio::ip::tcp::socket::shutdown_both, ec);
        s.close(ec);
    }
}

}  // namespace reprise::server
