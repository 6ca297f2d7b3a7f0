#include "modbus_rtu_driver/core/server/modbus_tcp_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "modbus_rtu_driver/core/modbus/mbap.h"

namespace modbus_rtu_driver {

namespace {

// A client that does not read its replies is closed once this much waits for it.
constexpr size_t kMaxPendingOutput = size_t{64} * 1024;

// A TCP socket bound to host:port (SO_REUSEADDR), listening when `listening`: its fd, or -1 with
// the reason and `in_use` set for EADDRINUSE. start() and canListen() bind alike.
int boundSocket(const std::string& host, uint16_t port, int flags, bool listening,
                std::string* error, bool* in_use) {
  *in_use = false;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  if (inet_pton(AF_INET, host.c_str(), &addr.sin_addr) != 1) {
    if (error) *error = "listen: '" + host + "' is not an IPv4 address";
    return -1;
  }
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | flags, 0);
  const int on = 1;
  if (fd >= 0 && setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on) == 0 &&
      bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0 &&
      (!listening || listen(fd, 16) == 0))
    return fd;
  const int err = errno;
  if (fd >= 0) close(fd);
  *in_use = err == EADDRINUSE;
  if (error)
    *error = "cannot listen on " + host + ":" + std::to_string(port) + ": " + std::strerror(err);
  return -1;
}

}  // namespace

ModbusTcpServer::ModbusTcpServer(TcpServerOptions options, Handler handler)
    : options_(std::move(options)), handler_(std::move(handler)) {}

ModbusTcpServer::~ModbusTcpServer() {
  stop();
}

bool ModbusTcpServer::canListen(const std::string& host, uint16_t port, std::string* error,
                                bool* in_use) {
  const int fd = boundSocket(host, port, 0, false, error, in_use);
  if (fd < 0) return false;
  close(fd);
  return true;
}

bool ModbusTcpServer::start(std::string* error) {
  auto fail = [&](const std::string& why) {
    if (error) *error = why;
    stop();
    return false;
  };
  address_in_use_ = false;
  allow_.clear();
  for (const std::string& entry : options_.allow) {
    AllowRule rule{};
    std::string why;
    if (!parseAllowEntry(entry, &rule.network, &rule.mask, &why)) return fail("allow: " + why);
    allow_.push_back(rule);
  }
  if (options_.max_clients < 1) return fail("max_clients: must be at least 1");
  if (!(options_.idle_timeout >= 0))
    return fail("idle_timeout: " + std::to_string(options_.idle_timeout) +
                " s is below 0 (0 = never)");
  std::string why;
  listen_fd_ =
      boundSocket(options_.host, options_.port, SOCK_NONBLOCK, true, &why, &address_in_use_);
  if (listen_fd_ < 0) return fail(why);
  sockaddr_in addr{};
  socklen_t len = sizeof addr;
  getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  bound_port_ = ntohs(addr.sin_port);
  wake_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (wake_fd_ < 0) return fail(std::string("eventfd: ") + std::strerror(errno));
  running_ = true;
  thread_ = std::thread(&ModbusTcpServer::run, this);
  return true;
}

void ModbusTcpServer::stop() {
  running_ = false;
  if (wake_fd_ >= 0) wake();
  if (thread_.joinable()) thread_.join();
  std::lock_guard<std::mutex> lock(mutex_);
  while (!clients_.empty()) closeClient(clients_.begin()->first);
  for (int* fd : {&listen_fd_, &wake_fd_}) {
    if (*fd >= 0) close(*fd);
    *fd = -1;
  }
}

void ModbusTcpServer::wake() const {
  const uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = write(wake_fd_, &one, sizeof one);
}

void ModbusTcpServer::dropClients() {
  drop_requested_ = true;
  wake();
}

ModbusTcpServer::Stats ModbusTcpServer::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  Stats s = stats_;
  s.connected = clients_.size();
  return s;
}

void ModbusTcpServer::run() {
  while (running_) {
    std::vector<pollfd> fds{{wake_fd_, POLLIN, 0}, {listen_fd_, POLLIN, 0}};
    std::vector<ClientId> ids;
    int timeout_ms = -1;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      timeout_ms = closeFinished(std::chrono::steady_clock::now());
      for (const auto& [id, c] : clients_) {
        // A half-closed client has nothing more to read (its socket would stay readable).
        const short in = c.read_closed ? 0 : POLLIN;
        fds.push_back({c.fd, static_cast<short>(in | (c.output.empty() ? 0 : POLLOUT)), 0});
        ids.push_back(id);
      }
    }
    if (poll(fds.data(), fds.size(), timeout_ms) < 0 && errno != EINTR) break;
    if (fds[0].revents & POLLIN) {
      uint64_t count;
      [[maybe_unused]] const ssize_t n = read(wake_fd_, &count, sizeof count);
    }
    if (!running_) break;
    if (drop_requested_.exchange(false)) {
      std::lock_guard<std::mutex> lock(mutex_);
      while (!clients_.empty()) closeClient(clients_.begin()->first);
      continue;
    }
    if (fds[1].revents & POLLIN) acceptClient();
    for (size_t i = 0; i < ids.size(); ++i)
      if (fds[i + 2].revents & (POLLIN | POLLHUP | POLLERR)) receive(ids[i]);
    // Replies given since the last turn (by any thread), and what a full socket held back.
    std::vector<ClientId> all;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (const auto& kv : clients_) all.push_back(kv.first);
    }
    for (ClientId id : all) flush(id);
  }
}

int ModbusTcpServer::closeFinished(std::chrono::steady_clock::time_point now) {
  using std::chrono::duration;
  using std::chrono::steady_clock;
  const bool idle_close = options_.idle_timeout > 0;
  const auto idle = std::chrono::duration_cast<steady_clock::duration>(
      duration<double>(idle_close ? options_.idle_timeout : 0.0));
  steady_clock::time_point next = steady_clock::time_point::max();
  std::vector<ClientId> done;
  for (const auto& [id, c] : clients_) {
    if (c.read_closed && c.unanswered == 0 && c.output.empty()) {
      done.push_back(id);  // everything it asked for is answered and sent
      continue;
    }
    if (!idle_close || c.unanswered > 0) continue;  // waiting for the bus is not idle
    const auto deadline = c.last_activity + idle;
    if (now >= deadline) {
      done.push_back(id);
      ++stats_.idle_closed;
    } else
      next = std::min(next, deadline);
  }
  for (ClientId id : done) closeClient(id);
  if (next == steady_clock::time_point::max()) return -1;
  const auto ms = std::chrono::ceil<std::chrono::milliseconds>(next - now).count();
  return static_cast<int>(std::max<long long>(1, std::min<long long>(ms, 60'000)));
}

void ModbusTcpServer::acceptClient() {
  sockaddr_in peer{};
  socklen_t len = sizeof peer;
  const int fd =
      accept4(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
  if (fd < 0) return;
  const uint32_t ip = ntohl(peer.sin_addr.s_addr);
  bool allowed = false;
  for (const AllowRule& r : allow_) allowed = allowed || (ip & r.mask) == r.network;
  char text[INET_ADDRSTRLEN] = "?";
  inet_ntop(AF_INET, &peer.sin_addr, text, sizeof text);
  std::lock_guard<std::mutex> lock(mutex_);
  if (!allowed || clients_.size() >= static_cast<size_t>(options_.max_clients)) {
    ++(allowed ? stats_.refused_too_many : stats_.refused_not_allowed);
    close(fd);
    return;
  }
  ++stats_.accepted;
  ++stats_.peers[text].connections;
  // A peer that vanished (power loss, cable) never sends FIN: keep-alive finds it.
  const int on = 1;
  setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &on, sizeof on);
  setsockopt(fd, IPPROTO_TCP, TCP_KEEPIDLE, &kKeepAliveIdle, sizeof kKeepAliveIdle);
  setsockopt(fd, IPPROTO_TCP, TCP_KEEPINTVL, &kKeepAliveInterval, sizeof kKeepAliveInterval);
  setsockopt(fd, IPPROTO_TCP, TCP_KEEPCNT, &kKeepAliveCount, sizeof kKeepAliveCount);
  Client c;
  c.fd = fd;
  c.peer = text;
  c.last_activity = std::chrono::steady_clock::now();
  clients_[next_id_++] = std::move(c);
}

void ModbusTcpServer::closeClient(ClientId id) {
  auto it = clients_.find(id);
  if (it == clients_.end()) return;
  close(it->second.fd);
  clients_.erase(it);
}

void ModbusTcpServer::receive(ClientId id) {
  // recv runs without the lock: replies from other threads are not held up by it. The fd stays
  // this client's meanwhile, as only this thread (the poll loop) closes clients.
  int fd = -1;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = clients_.find(id);
    if (it == clients_.end()) return;
    if (it->second.read_closed) {  // POLLHUP / POLLERR after its FIN: the connection is gone
      closeClient(id);
      return;
    }
    fd = it->second.fd;
  }
  uint8_t buf[1024];
  const ssize_t n = recv(fd, buf, sizeof buf, 0);
  const int err = errno;
  std::vector<Bytes> frames;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = clients_.find(id);
    if (it == clients_.end()) return;
    Client& c = it->second;
    if (n == 0 && (c.unanswered > 0 || !c.output.empty())) {
      // FIN after its requests (a half-close): their answers still go out, then it is closed.
      c.read_closed = true;
      ++stats_.half_closed;
      return;
    }
    if (n == 0 || (n < 0 && err != EAGAIN && err != EINTR)) {
      closeClient(id);  // the client went (or its socket failed): its pending replies go too
      return;
    }
    if (n < 0) return;
    c.last_activity = std::chrono::steady_clock::now();
    c.input.insert(c.input.end(), buf, buf + n);
    for (;;) {
      const int length = mbapLengthFromHeader(c.input);
      if (length < 0) {
        ++stats_.malformed;
        closeClient(id);
        return;
      }
      if (length == 0 || c.input.size() < static_cast<size_t>(length)) break;
      frames.emplace_back(c.input.begin(), c.input.begin() + length);
      c.input.erase(c.input.begin(), c.input.begin() + length);
      ++stats_.peers[c.peer].requests;
    }
  }
  for (const Bytes& adu : frames) handleFrame(id, adu);
}

void ModbusTcpServer::handleFrame(ClientId id, const Bytes& adu) {
  Incoming in;
  in.client = id;
  in.transaction = mbapTransaction(adu);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = clients_.find(id);
    if (it == clients_.end()) return;
    in.peer = it->second.peer;
    ++it->second.unanswered;  // every path below answers exactly once (reply() counts it down)
  }
  const Bytes rtu = mbapToRtu(adu);  // unit, PDU, CRC: what decodeRequest reads
  const uint8_t unit = rtu[0], function = rtu[1];
  auto refuse = [&](uint8_t code) { reply(in, encodeException(unit, function, code)); };
  // Read-only refuses a write as such, whatever its fields: before they are decoded or checked.
  if (options_.refuse_writes && isKnownFunction(function) &&
      !isReadFunction(static_cast<FunctionCode>(function)))
    return refuse(kIllegalFunction);
  if (!isKnownFunction(function)) return refuse(kIllegalFunction);
  std::optional<Request> request = decodeRequest(rtu);
  if (!request) return refuse(kIllegalDataValue);
  if (!request->validate().empty()) {
    const bool broadcast_read = unit == kBroadcastAddress && isReadFunction(request->function);
    if (broadcast_read) return refuse(kIllegalFunction);
    // A quantity that is fine from address 0 but runs past 65535 from this start: 02.
    Request from_zero = *request;
    from_zero.address = 0;
    return refuse(from_zero.validate().empty() ? kIllegalDataAddress : kIllegalDataValue);
  }
  in.request = std::move(*request);
  handler_(in);
}

void ModbusTcpServer::replyException(const Incoming& in, uint8_t code) {
  reply(in, encodeException(in.request.slave, static_cast<uint8_t>(in.request.function), code));
}

void ModbusTcpServer::reply(const Incoming& in, const Bytes& rtu_adu) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = clients_.find(in.client);
    if (it == clients_.end()) return;
    Client& c = it->second;
    if (c.unanswered > 0) --c.unanswered;
    c.last_activity = std::chrono::steady_clock::now();  // idle time counts from the answer
    if (rtu_adu.size() > 1 && (rtu_adu[1] & 0x80)) ++stats_.peers[c.peer].exceptions;
    const Bytes mbap = rtuToMbap(in.transaction, rtu_adu);
    c.output.insert(c.output.end(), mbap.begin(), mbap.end());
  }
  wake();
}

void ModbusTcpServer::flush(ClientId id) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = clients_.find(id);
  if (it == clients_.end() || it->second.output.empty()) return;
  Client& c = it->second;
  const ssize_t n = send(c.fd, c.output.data(), c.output.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  if (n > 0) c.output.erase(c.output.begin(), c.output.begin() + n);
  const bool failed = n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR;
  if (failed || c.output.size() > kMaxPendingOutput) closeClient(id);
}

}  // namespace modbus_rtu_driver
