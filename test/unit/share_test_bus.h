// What the share's tests run against: a bus of in-memory devices behind a real BusScheduler,
// a ShareGateway on 127.0.0.1 with an ephemeral port, and a blocking Modbus TCP client with
// bounded waits (real sockets, no mocks of the server).
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/core/modbus/mbap.h"
#include "modbus_rtu_driver/core/server/share_gateway.h"

namespace modbus_rtu_driver {

// Slave 1 holds 100 registers and 100 coils; slave 5 answers every request with exception 02;
// others never answer (timeout). `hold()` keeps the next transaction on the bus until
// `release()`; `open = false` makes the port fail to open.
class MemoryBus : public Transport {
 public:
  std::map<uint16_t, uint16_t> registers, coils;
  bool open = true;

  // A late-reply guard on slave `guarded` (docs/share.md): guardLeft says `guard_left` for its
  // requests; one attempt of any request takes at most `attempt_seconds`. Set before the bus
  // thread starts; the bus thread's afterwards.
  uint8_t guarded = 0;
  double guard_left = 0, attempt_seconds = 0.04;
  // The next `owed` reads of slave 1 run in parts (Transport::executeAttempts) lose their
  // answer with a retry owed; `on_owed` runs then.
  int owed = 0;
  std::function<void()> on_owed;

  double guardLeft(const Request& next) const override {
    return next.slave == guarded ? guard_left : 0;
  }
  double attemptSeconds(const Request& /*request*/) const override { return attempt_seconds; }
  Result executeAttempts(const Request& r, int first, int most) override {
    if (most < 0 || r.slave != 1 || owed == 0) return execute(r);
    --owed;
    {
      std::lock_guard<std::mutex> lock(m_);
      ++executed_;
      order_.push_back(r.slave);
    }
    if (on_owed) on_owed();
    Result lost =
        Result::failure(ErrorKind::kTimeout, "no reply to attempt " + std::to_string(first));
    lost.retry_owed = true;
    return lost;
  }
  // The slave of every transaction started, in order.
  std::vector<uint8_t> order() {
    std::lock_guard<std::mutex> lock(m_);
    return order_;
  }

  Result execute(const Request& r) override {
    std::unique_lock<std::mutex> lock(m_);
    ++executed_;
    order_.push_back(r.slave);
    cv_.notify_all();
    cv_.wait(lock, [&] { return !held_; });
    if (r.slave == kBroadcastAddress) return Result::success();
    if (r.slave == 5) return Result::failure(ErrorKind::kException, "refused", kIllegalDataAddress);
    if (r.slave != 1) return Result::failure(ErrorKind::kTimeout, "no reply");
    auto& table = isBitFunction(r.function) ? coils : registers;
    std::vector<uint16_t> values;
    for (uint16_t i = 0; i < r.count; ++i) {
      if (isReadFunction(r.function))
        values.push_back(table[static_cast<uint16_t>(r.address + i)]);
      else
        table[static_cast<uint16_t>(r.address + i)] = r.values[i];
    }
    return Result::success(isReadFunction(r.function) ? values : r.values);
  }
  bool connect(std::string* error) override {
    if (!open && error) *error = "cannot open /dev/memory";
    return open;
  }
  bool connected() const override { return open; }

  void hold() {
    std::lock_guard<std::mutex> lock(m_);
    held_ = true;
  }
  void release() {
    std::lock_guard<std::mutex> lock(m_);
    held_ = false;
    cv_.notify_all();
  }
  // Waits (bounded) until `n` transactions have started.
  bool awaitExecuted(int n) {
    std::unique_lock<std::mutex> lock(m_);
    return cv_.wait_for(lock, std::chrono::seconds(10), [&] { return executed_ >= n; });
  }
  int executed() {
    std::lock_guard<std::mutex> lock(m_);
    return executed_;
  }
  uint16_t reg(uint16_t address) {
    std::lock_guard<std::mutex> lock(m_);
    return registers[address];
  }

 private:
  std::mutex m_;
  std::condition_variable cv_;
  bool held_ = false;
  int executed_ = 0;
  std::vector<uint8_t> order_;
};

// A Modbus TCP client on a blocking socket; every wait is bounded.
class TcpClient {
 public:
  explicit TcpClient(uint16_t port) {
    fd_ = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~TcpClient() { close(fd_); }
  bool connected() const { return connected_; }
  int fd() const { return fd_; }

  bool sendBytes(const Bytes& b) {
    return ::send(fd_, b.data(), b.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(b.size());
  }
  bool send(uint16_t transaction, const Request& r) {
    return sendBytes(rtuToMbap(transaction, encodeRequest(r)));
  }
  // One whole MBAP frame; empty on timeout or when the server closed the connection.
  Bytes receive(double seconds = 10.0) {
    Bytes frame;
    while (true) {
      const int need = mbapLengthFromHeader(frame);
      if (need < 0) return frame;  // not MBAP: the caller's assertion shows it
      const size_t want = need == 0 ? 6 : static_cast<size_t>(need);
      if (frame.size() >= want && need > 0) return frame;
      uint8_t byte;
      if (!readByte(&byte, seconds)) return {};
      frame.push_back(byte);
    }
  }
  // True when the server closed the connection within `seconds` (bytes before are skipped).
  bool closedByServer(double seconds = 10.0) {
    uint8_t byte;
    while (readByte(&byte, seconds)) {
    }
    return eof_;
  }
  // The request's reply as an RTU ADU (with a fresh CRC), for comparison with encodeReply.
  static Bytes asRtu(const Bytes& mbap) { return mbap.size() < 8 ? Bytes{} : mbapToRtu(mbap); }

 private:
  bool readByte(uint8_t* byte, double seconds) {
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, static_cast<int>(seconds * 1000)) <= 0) return false;
    const ssize_t n = recv(fd_, byte, 1, 0);
    eof_ = n <= 0;
    return n == 1;
  }
  int fd_ = -1;
  bool connected_ = false, eof_ = false;
};

// The complete frames a server can take from `input` before a header that is not MBAP.
inline std::vector<Bytes> mbapFramesIn(Bytes input) {
  std::vector<Bytes> frames;
  for (;;) {
    const int n = mbapLengthFromHeader(input);
    if (n <= 0 || input.size() < static_cast<size_t>(n)) return frames;
    frames.emplace_back(input.begin(), input.begin() + n);
    input.erase(input.begin(), input.begin() + n);
  }
}

// Removes from `unanswered` the frame `reply` answers (its transaction id and unit, the same
// function or its exception); false when it answers none of them. A frame whose function
// equals the reply's is taken before one whose exception it could be: a client may send
// function 0x86 itself (answered "illegal function", 0x86) beside an FC06 with the same
// transaction id and unit, and the FC06's echo may come after it.
inline bool takeAnswered(std::vector<Bytes>* unanswered, const Bytes& reply) {
  if (reply.size() < 8) return false;
  for (const bool exception : {false, true}) {
    for (auto q = unanswered->begin(); q != unanswered->end(); ++q) {
      const uint8_t function = exception ? ((*q)[7] | 0x80) : (*q)[7];
      if (mbapTransaction(*q) == mbapTransaction(reply) && (*q)[6] == reply[6] &&
          reply[7] == function) {
        unanswered->erase(q);
        return true;
      }
    }
  }
  return false;
}

// The share on an ephemeral port over a MemoryBus.
struct ShareFixture {
  // `transaction_time` and `clock`: the answer bound's (none without them).
  explicit ShareFixture(ShareConfig config = {},
                        ShareGateway::TransactionTime transaction_time = nullptr,
                        Clock& clock = Clock::steady())
      : bus_thread(bus) {
    config.server.port = 0;
    config.enabled = true;
    gateway = std::make_unique<ShareGateway>(
        bus_thread, config,
        [](uint8_t slave) { return slave == 1 ? std::string("memory") : std::string(); },
        std::move(transaction_time), clock);
  }
  ~ShareFixture() {
    bus.release();
    bus_thread.stop();  // pending answers call into the gateway: stop the bus first
    gateway.reset();
  }
  bool start() {
    bus_thread.start();
    std::string error;
    return gateway->start(&error);
  }
  uint16_t port() { return gateway->server().port(); }

  MemoryBus bus;
  BusScheduler bus_thread;
  std::unique_ptr<ShareGateway> gateway;
};

}  // namespace modbus_rtu_driver
