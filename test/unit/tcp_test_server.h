// A TCP server on 127.0.0.1 for the transports' tests: each accepted connection is handed to
// `serve` on the server's own thread (one at a time), then closed. Frames are read with the
// core's own reader, by the length their header announces.
#pragma once

#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "modbus_rtu_driver/core/fd_io.h"
#include "modbus_rtu_driver/core/mbap.h"

namespace modbus_rtu_driver {

class TestTcpServer {
 public:
  explicit TestTcpServer(std::function<void(int fd)> serve) : serve_(std::move(serve)) {
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
  // Every frame a serve function read with readRtu / readMbap, in order.
  std::vector<Bytes> received() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return received_;
  }
  // One request frame (5 s at most); empty when the client closed or nothing came.
  Bytes readRtu(int fd) {
    return read(fd, [](const Bytes& b) { return static_cast<long>(requestLengthFromHeader(b)); });
  }
  Bytes readMbap(int fd) {
    return read(fd, [](const Bytes& b) { return static_cast<long>(mbapLengthFromHeader(b)); });
  }
  static void write(int fd, const Bytes& bytes) {
    ssize_t n = ::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    (void)n;
  }

 private:
  Bytes read(int fd, const std::function<long(const Bytes&)>& length_of) {
    Bytes frame;
    if (readFrame(fd, 5.0, 5.0, length_of, 1, 300, &frame, nullptr) != ReadStatus::kComplete)
      return {};
    std::lock_guard<std::mutex> lock(mutex_);
    received_.push_back(frame);
    return frame;
  }
  void run() {
    while (!stop_) {
      pollfd p{listen_fd_, POLLIN, 0};
      if (poll(&p, 1, 20) <= 0) continue;
      const int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd < 0) continue;
      ++accepted_;
      serve_(fd);
      close(fd);
    }
  }

  std::function<void(int)> serve_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<int> accepted_{0};
  mutable std::mutex mutex_;
  std::vector<Bytes> received_;
  std::thread thread_;
};

}  // namespace modbus_rtu_driver
