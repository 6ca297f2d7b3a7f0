// Sharing a bus: Modbus TCP clients (mbpoll, a commissioning tool, an HMI) reach the devices of
// a bus that a BusScheduler owns. Each valid request is queued on the bus after the writes of
// ROS and ahead of the polls (BusScheduler::submitShared) and answered when it has run, with
// the client's transaction id and the slave address as unit id. What a client may see:
//   01 a write while read_only, even a malformed one (also a read at unit 0, a function the
//   server does not know);
//   06 the share's queue is full (max_queue requests waiting for the bus, all clients together);
//   0A the port is not open (or the bus is stopping; requests still queued when the share stops
//   are refused this way, unsent, as their connections close); 0B the device did not answer
//   properly (timeout, CRC, garbled reply) after the link's retries, or the request could not
//   start early enough to be answered within the answer bound (then it is never sent); any other
//   code is the device's own.
// The answer bound (docs/share.md, "How long an answer takes"): every request is answered
// within it of its arrival. A request gets a latest start (arrival + bound - its own longest
// transaction); one still queued then is answered 0B by the gateway's own thread, whatever the
// bus is doing, and skipped unsent when the bus reaches it.
// Unit 0 is a broadcast: nobody answers on the bus, so a write is answered with its normal
// reply once it was sent (sent, not confirmed by any device), and the bus then stays quiet for
// `broadcast_turnaround` s (the serial line spec's turnaround delay, 100-200 ms: the devices are
// still carrying the broadcast out, and LC boards even answer address 0) before its next
// request; the client's answer comes after that delay.
// ROS-free: the node's share and the simulator's TCP side both use it.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/core/server/modbus_tcp_server.h"

namespace modbus_rtu_driver {

// The gateway exception for a failed transaction, or the device's own exception code.
uint8_t shareExceptionFor(const Result& result);
// What the client gets for `request` once it ran with `result`: an RTU ADU (reply or exception).
Bytes shareReplyFor(const Request& request, const Result& result);

class ShareGateway {
 public:
  // `device_of(slave)` names the configured device at that address ("" when none): its health
  // counts the shared requests. The bus must stop before the gateway goes (pending answers
  // call back into it).
  // `transaction_time(request)`: the longest a request's transaction can take once it starts
  // (Link::worstTransactionSeconds); without it there is no answer bound. `clock`: what the
  // bound is measured on.
  using TransactionTime = std::function<double(const Request&)>;
  ShareGateway(BusScheduler& scheduler, ShareConfig config,
               std::function<std::string(uint8_t)> device_of = nullptr,
               TransactionTime transaction_time = nullptr, Clock& clock = Clock::steady());
  ~ShareGateway();
  // Checks the configuration (answer_within against the longest transaction, naming both) and
  // listens.
  bool start(std::string* error);
  // start() without listening: requests come only through forward() (the fail-safe's
  // simulation, which has no sockets).
  bool open(std::string* error);
  // What a client's request gets: the RTU ADU of its reply or exception, exactly once (on the
  // bus thread, the gateway's thread at the bound, or the caller's when refused at once).
  using Answer = std::function<void(const Bytes& rtu_adu)>;
  // One client's request, on its way to the bus (the server's thread calls it for each request;
  // never waits for the bus). `ran`, if given, gets the transaction's outcome on the bus thread
  // right after it (the simulation's model); `tag` is the job's (BusScheduler::currentTag).
  void forward(const Request& request, Answer answer,
               std::function<void(const Result&)> ran = nullptr, uint64_t tag = 0);
  // Closes the server and refuses every request still queued on the bus (unsent): none runs
  // after this returns, except the one on the bus right now.
  void stop();
  ModbusTcpServer& server() { return *server_; }
  // Called on the bus thread after each client's write, with its outcome (confirmed by its
  // normal reply, unit 0: sent; or failed, its answer perhaps lost), before any later job runs:
  // the node's fail-safe takes a confirmed one as a command, not as a device restart, and a
  // lost answer's channels as unknown (docs/failsafe.md). Before start().
  void onWriteDone(std::function<void(const Request&, const Result&)> done) {
    wrote_ = std::move(done);
  }
  int queued() const { return in_flight_.load(); }
  // s: every request is answered within this; 0 without a bound. Valid after start().
  double answerBound() const { return bound_; }
  // The longest transaction a client's request can take here (the largest read or write, or a
  // broadcast with its turnaround, to any unit); the default bound is twice this.
  double longestTransaction() const;
  // Requests answered 0B at their latest start, never sent.
  uint64_t expired() const { return expired_.load(); }
  // Requests run while another device's late-reply guard held the line (docs/share.md).
  uint64_t ranInGuards() const { return scheduler_.ranInGuards(); }
  // Of those, reads whose retries went after the guarded request.
  uint64_t cutInGuards() const { return scheduler_.cutInGuards(); }

 private:
  // A request between its arrival and its answer: queued, on the bus, or answered 0B unsent.
  struct Waiting {
    enum State { kQueued, kRunning, kExpired, kDone };
    Request request;
    Answer answer;
    Clock::time_point start_by;
    std::atomic<int> state{kQueued};
  };
  void handle(const ModbusTcpServer::Incoming& in);
  // Answers 0B once, if it is still queued (any thread).
  void expire(Waiting& w);
  // The gateway's thread: answers each request still queued at its latest start.
  void expireLoop();
  double ownTransaction(const Request& sent) const;

  BusScheduler& scheduler_;
  ShareConfig config_;
  std::function<std::string(uint8_t)> device_of_;
  std::function<void(const Request&, const Result&)> wrote_;
  TransactionTime transaction_time_;
  Clock& clock_;
  std::unique_ptr<ModbusTcpServer> server_;
  std::atomic<int> in_flight_{0};
  std::atomic<uint64_t> expired_{0};
  double bound_ = 0.0;

  std::mutex deadlines_mutex_;  // the three below
  std::condition_variable deadlines_cv_;
  std::multimap<Clock::time_point, std::shared_ptr<Waiting>> deadlines_;
  bool stopping_ = false;
  std::thread expiry_thread_;
};

}  // namespace modbus_rtu_driver
