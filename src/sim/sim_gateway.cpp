#include "modbus_rtu_driver/sim/sim_gateway.h"

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace modbus_rtu_driver {

bool SimGateway::listen(int port, std::string* error) {
  port_ = port;
  if (openListener(error)) return true;
  port_ = 0;
  return false;
}

bool SimGateway::openListener(std::string* error) {
  listen_fd_ = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  const int on = 1;
  setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);  // back up at once
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = htons(static_cast<uint16_t>(port_));
  socklen_t len = sizeof addr;
  if (listen_fd_ < 0 || bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      ::listen(listen_fd_, 4) != 0 ||
      getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
    if (error)
      *error = "rtu+tcp: cannot listen on 127.0.0.1:" + std::to_string(port_) + ": " +
               std::strerror(errno);
    if (listen_fd_ >= 0) ::close(listen_fd_);
    listen_fd_ = -1;
    return false;
  }
  port_ = ntohs(addr.sin_port);
  return true;
}

void SimGateway::close() {
  for (int fd : connections_) ::close(fd);
  connections_.clear();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  listen_fd_ = -1;
}

void SimGateway::addPollFds(std::vector<pollfd>* fds) const {
  if (listen_fd_ >= 0) fds->push_back({listen_fd_, POLLIN, 0});
  for (int fd : connections_) fds->push_back({fd, POLLIN, 0});
}

bool SimGateway::receive(Clock::time_point now, Bytes* in) {
  if (!enabled()) return false;
  if (listen_fd_ < 0 && now >= down_until_) openListener(nullptr);  // rebooted
  for (int c; listen_fd_ >= 0 &&
              (c = accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC)) >= 0;) {
    const int on = 1;
    setsockopt(c, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);
    connections_.push_back(c);
    ++accepted_;
  }
  const size_t before = in->size();
  for (size_t i = 0; i < connections_.size();) {
    uint8_t buf[512];
    const ssize_t n = recv(connections_[i], buf, sizeof buf, MSG_DONTWAIT);
    if (n > 0) {
      in->insert(in->end(), buf, buf + n);
      continue;  // read until it has nothing more
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) {
      ++i;
      continue;
    }
    ::close(connections_[i]);  // the client went away
    connections_.erase(connections_.begin() + static_cast<long>(i));
  }
  return in->size() > before;
}

void SimGateway::send(const uint8_t* data, size_t size) {
  for (size_t i = 0; i < connections_.size();) {
    if (::send(connections_[i], data, size, MSG_NOSIGNAL | MSG_DONTWAIT) ==
        static_cast<ssize_t>(size)) {
      ++i;
      continue;
    }
    ::close(connections_[i]);
    connections_.erase(connections_.begin() + static_cast<long>(i));
  }
}

// shutdown() first: command() may run while the line thread polls these descriptors, and a
// close alone would leave them open (and listening) until that poll returns.
void SimGateway::drop(double down_seconds, Clock::time_point now) {
  dropped_ += connections_.size();
  for (int fd : connections_) {
    shutdown(fd, SHUT_RDWR);
    ::close(fd);
  }
  connections_.clear();
  if (down_seconds <= 0) return;
  if (listen_fd_ >= 0) {
    shutdown(listen_fd_, SHUT_RDWR);
    ::close(listen_fd_);
  }
  listen_fd_ = -1;
  down_until_ = now + std::chrono::duration_cast<Clock::duration>(
                          std::chrono::duration<double>(down_seconds));
}

std::string SimGateway::status() const {
  return "port " + std::to_string(port_) + " connections " + std::to_string(connections_.size()) +
         " accepted " + std::to_string(accepted_) + " dropped " + std::to_string(dropped_);
}

}  // namespace modbus_rtu_driver
