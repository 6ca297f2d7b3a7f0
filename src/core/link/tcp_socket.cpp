#include "modbus_rtu_driver/core/link/tcp_socket.h"

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace modbus_rtu_driver {

namespace {

// Waits for a non-blocking connect; 0 or an errno.
int finishConnect(int fd) {
  pollfd p{fd, POLLOUT, 0};
  int ready;
  do {
    ready = poll(&p, 1, static_cast<int>(kTcpConnectTimeout * 1000));
  } while (ready == -1 && errno == EINTR);
  if (ready == 0) return ETIMEDOUT;
  if (ready < 0) return errno;
  int so_error = 0;
  socklen_t len = sizeof so_error;
  getsockopt(fd, SOL_SOCKET, SO_ERROR, &so_error, &len);
  return so_error;
}

// A connect to a local port nobody listens on can pick that very port as its own and connect
// to itself (TCP simultaneous open): that is no gateway.
bool connectedToItself(int fd) {
  sockaddr_storage self{}, peer{};
  socklen_t self_len = sizeof self, peer_len = sizeof peer;
  return getsockname(fd, reinterpret_cast<sockaddr*>(&self), &self_len) == 0 &&
         getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &peer_len) == 0 &&
         self_len == peer_len && std::memcmp(&self, &peer, self_len) == 0;
}

void tune(int fd) {
  const int on = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);  // one frame, one segment, now
  setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &on, sizeof on);
  const int idle = 5, interval = 2, probes = 3;  // an idle dead peer is noticed in ~11 s
  setsockopt(fd, IPPROTO_TCP, TCP_KEEPIDLE, &idle, sizeof idle);
  setsockopt(fd, IPPROTO_TCP, TCP_KEEPINTVL, &interval, sizeof interval);
  setsockopt(fd, IPPROTO_TCP, TCP_KEEPCNT, &probes, sizeof probes);
  // A request the peer never acknowledges fails the connection after 5 s (not ~15 min).
  const unsigned user_timeout_ms = 5000;
  setsockopt(fd, IPPROTO_TCP, TCP_USER_TIMEOUT, &user_timeout_ms, sizeof user_timeout_ms);
}

}  // namespace

int connectTcp(const std::string& host, int port, std::string* error) {
  const std::string where = host + ":" + std::to_string(port);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const int rc = getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found);
  if (rc != 0) {
    if (error) *error = "cannot resolve " + host + ": " + gai_strerror(rc);
    return -1;
  }
  int last_error = ECONNREFUSED;
  int fd = -1;
  for (addrinfo* a = found; a && fd < 0; a = a->ai_next) {
    fd = socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) {
      last_error = errno;
      continue;
    }
    int err = ::connect(fd, a->ai_addr, a->ai_addrlen) == 0 ? 0 : errno;
    if (err == EINPROGRESS) err = finishConnect(fd);
    if (err == 0 && connectedToItself(fd)) err = ECONNREFUSED;
    if (err != 0) {
      last_error = err;
      close(fd);
      fd = -1;
    }
  }
  freeaddrinfo(found);
  if (fd < 0) {
    if (error) *error = "cannot connect to " + where + ": " + std::strerror(last_error);
    return -1;
  }
  fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  tune(fd);
  return fd;
}

bool sendAll(int fd, const Bytes& bytes) {
  size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    sent += static_cast<size_t>(n);
  }
  return true;
}

long discardWaiting(int fd) {
  long dropped = 0;
  for (;;) {
    uint8_t junk[512];
    const ssize_t n = recv(fd, junk, sizeof junk, MSG_DONTWAIT);
    if (n > 0) {
      dropped += n;
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return dropped;
    return -1;  // closed (0) or failed
  }
}

bool closedByPeer(int fd) {
  uint8_t byte;
  ssize_t n;
  do {
    n = recv(fd, &byte, 1, MSG_PEEK | MSG_DONTWAIT);
  } while (n < 0 && errno == EINTR);
  return n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK);
}

}  // namespace modbus_rtu_driver
