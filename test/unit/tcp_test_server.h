// A TCP server on 127.0.0.1 for the transports' tests: each accepted connection is handed to
// `serve` on the server's own thread (one at a time), then closed. It reads the framing its link
// sends (RTU frames through a transparent gateway, or MBAP), with the core's own reader, by the
// length their header announces. Below it: the serve functions the tests share.
#pragma once

#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "modbus_rtu_driver/core/config/link_config.h"
#include "modbus_rtu_driver/core/link/fd_io.h"
#include "modbus_rtu_driver/core/modbus/mbap.h"

namespace modbus_rtu_driver {

enum class TcpFraming { kRtu, kMbap };  // rtu+tcp:// or tcp://

// The link's settings for a test server on 127.0.0.1:port: fast line, one retry.
inline LinkConfig testTcpLinkConfig(TcpFraming framing, int port) {
  LinkConfig c;
  c.port = (framing == TcpFraming::kRtu ? "rtu+tcp://127.0.0.1:" : "tcp://127.0.0.1:") +
           std::to_string(port);
  c.baud = 115200;
  c.retries = 1;
  c.network_allowance = 0.2;
  return c;
}

class TestTcpServer {
 public:
  using Serve = std::function<void(TestTcpServer& server, int fd)>;

  TestTcpServer(TcpFraming framing, Serve serve) : framing_(framing), serve_(std::move(serve)) {
    listen_fd_ = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof addr;
    bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    ::listen(listen_fd_, 4);
    getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(addr.sin_port);
    thread_ = std::thread([this] { run(); });
  }
  ~TestTcpServer() {
    stop_ = true;
    thread_.join();
    close(listen_fd_);
  }
  int port() const { return port_; }
  int accepted() const { return accepted_; }
  // Every frame a serve function read with readRequest, in order.
  std::vector<Bytes> received() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return received_;
  }
  // One request frame (5 s at most); empty when the client closed or nothing came.
  Bytes readRequest(int fd) {
    const auto length_of = [this](const Bytes& b) {
      return static_cast<long>(framing_ == TcpFraming::kRtu ? requestLengthFromHeader(b)
                                                            : mbapLengthFromHeader(b));
    };
    Bytes frame;
    if (readFrame(fd, 5.0, 5.0, length_of, 1, 300, &frame, nullptr) != ReadStatus::kComplete)
      return {};
    std::lock_guard<std::mutex> lock(mutex_);
    received_.push_back(frame);
    return frame;
  }
  static void write(int fd, const Bytes& bytes) {
    ssize_t n = ::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    (void)n;
  }

 private:
  void run() {
    while (!stop_) {
      pollfd p{listen_fd_, POLLIN, 0};
      if (poll(&p, 1, 20) <= 0) continue;
      const int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd < 0) continue;
      ++accepted_;
      serve_(*this, fd);
      close(fd);
    }
  }

  TcpFraming framing_;
  Serve serve_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<int> accepted_{0};
  mutable std::mutex mutex_;
  std::vector<Bytes> received_;
  std::thread thread_;
};

// Hears every request until the client closes, and answers none.
inline TestTcpServer::Serve hearingOnly() {
  return [](TestTcpServer& server, int fd) {
    while (!server.readRequest(fd).empty()) {
    }
  };
}

// Answers every request with `reply_of(request)` until the client closes; an empty reply closes
// the connection.
inline TestTcpServer::Serve answering(std::function<Bytes(const Bytes& request)> reply_of) {
  return [reply_of](TestTcpServer& server, int fd) {
    for (Bytes request; !(request = server.readRequest(fd)).empty();) {
      const Bytes reply = reply_of(request);
      if (reply.empty()) return;
      TestTcpServer::write(fd, reply);
    }
  };
}

// A gateway that reboots: its first connection dies mid-request (the request read, never
// answered); later ones are served by `then`.
inline TestTcpServer::Serve droppingTheFirstConnection(TestTcpServer::Serve then) {
  return [then](TestTcpServer& server, int fd) {
    if (server.accepted() > 1) return then(server, fd);
    server.readRequest(fd);
  };
}

}  // namespace modbus_rtu_driver
