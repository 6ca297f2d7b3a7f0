// What every bus link shares, whatever carries its frames (serial port, Modbus TCP, RTU over
// TCP): the retry rule (only lost answers, only repeatable requests), the statistics, the silence
// between frames, and the late-reply guard. A subclass runs one attempt on its medium.
// Only the bus thread calls execute/connect/disconnect; stats() is safe from any thread.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "modbus_rtu_driver/core/config/link_config.h"
#include "modbus_rtu_driver/core/link/fd_io.h"
#include "modbus_rtu_driver/core/link/link_types.h"
#include "modbus_rtu_driver/core/link/transport.h"
#include "modbus_rtu_driver/core/modbus/frame.h"

namespace modbus_rtu_driver {

struct LinkStats {
  uint64_t requests = 0;  // transactions asked for (not counting retries)
  uint64_t attempts = 0;  // frames sent, retries included
  uint64_t ok = 0;        // transactions that succeeded (after retries, if any)
  uint64_t failed = 0;    // transactions that failed for good
  uint64_t broadcasts = 0;
  // Failed attempts by kind, retried ones included (a timeout retried once counts 2 if both
  // attempts failed, 1 if the retry got through).
  uint64_t timeouts = 0;
  uint64_t crc_errors = 0;
  uint64_t wrong_address = 0;
  uint64_t exceptions = 0;
  uint64_t malformed = 0;
  uint64_t io_errors = 0;
  uint64_t retries = 0;
  uint64_t reconnects = 0;   // successful connects after the first
  uint64_t stale_bytes = 0;  // thrown away before a request: late replies, noise
  double last_latency = 0;   // s, request sent to reply decoded, successful transactions
  double mean_latency = 0;   // s
  double max_latency = 0;    // s
};

// One frame as the link put it on its medium or took it off, and when (CLOCK_MONOTONIC, the
// clock of the simulator's --timestamps): a request from just before its write to the write's
// return, a reply (or what came of one) from its first byte read to its last. For the wire log
// and the benchmark's split of the line's time.
struct WireEvent {
  bool outgoing = false;
  std::chrono::steady_clock::time_point first{}, last{};
  Bytes frame;
  // The bus thread's CPU seconds at the event (a request: before its write; a reply: after its
  // last read), less what keepGap spun: between a reply and the next request, the CPU the
  // driver's own work took.
  double cpu = 0;
  // A request: how late the sleep for the gap before it woke (0 without one), the machine's
  // part of the driver's turnaround.
  double gap_late = 0;
  // A request: how long the late-reply guard held it after a failed transaction (0: not).
  double guard_wait = 0;
};
using WireObserver = std::function<void(const WireEvent&)>;
// "tx|rx FIRST LAST HEX cpu=SECONDS[ late=SECONDS guard=SECONDS]" (late and guard: requests),
// the first four the simulator's --timestamps form.
std::string formatWireEvent(const WireEvent& event);

class Link : public Transport {
 public:
  // `target` is config.port parsed (makeLink passes the one it parsed); without one, the link
  // parses the port itself (a link built from its config alone, as tests do).
  explicit Link(LinkConfig config, LinkTarget target = {})
      : config_(std::move(config)),
        target_(target.type ? std::move(target) : linkTargetOf(config_.port)) {}
  Link(const Link&) = delete;
  Link& operator=(const Link&) = delete;

  // Checks and encodes the request (once: EncodedRequest), retries lost answers of repeatable
  // requests with the same frame, keeps the statistics.
  Result execute(const Request& request) final;
  Result executeAttempts(const Request& request, int first, int most) final;
  void awaitLineFree() override {
    if (connected()) keepGap();
  }
  // The response timeout for `slave` is raised by its reply delay (the LD58A08 can wait up to
  // 1000 ms before answering).
  void setReplyDelay(uint8_t slave, double seconds) { reply_delay_[slave] = seconds; }
  const LinkConfig& config() const { return config_; }
  // The longest a transaction of `request` can take once it starts: each attempt (the retries
  // of a repeatable request whose answer is lost) with the gap before its frame, the frame, the
  // response timeout and the longest reply ended by one byte timeout, then the late-reply guard
  // (0 for a request Request::validate refuses). A broadcast: the gap and the frame. A device
  // that sends its reply byte by byte just inside the byte timeout could take longer. Any
  // thread, once the reply delays are set (before the bus starts).
  double worstTransactionSeconds(const Request& request) const;
  // Bus thread.
  double guardLeft(const Request& next) const override;
  double lineSeconds(const Request& request) const override;
  double attemptSeconds(const Request& request) const override;
  LinkStats stats() const;
  // What the port names: its kind (LinkType: name, traits) and address.
  const LinkTarget& target() const { return target_; }
  // True when a USB adapter accepted ASYNC_LOW_LATENCY (serial only). Any thread.
  virtual bool lowLatency() const { return false; }
  // Called on the bus thread with every frame sent and every reply read; set it before the bus
  // starts. It should only copy the event and hand it on.
  void setWireObserver(WireObserver observer) { wire_observer_ = std::move(observer); }

 protected:
  // One request out and its reply in (the line prepared first); a kIo result disconnects.
  // Every attempt of a transaction gets the same frame, encoded once by execute.
  virtual Result attempt(const EncodedRequest& request) = 0;
  // Sends a request nobody answers; success once it is out.
  virtual Result sendBroadcast(const EncodedRequest& request) = 0;
  // False for a medium whose replies carry their request's id (Modbus TCP): no guard waits.
  virtual bool guardsLateReplies() const { return true; }
  // Silence kept between frames on the (far) serial line.
  virtual double minGap() const { return effectiveMinGap(config_); }
  // Seconds to wait for the first byte of the reply (sized by the frame's length).
  virtual double responseTimeout(const EncodedRequest& request) const;

  // Call after each successful connect: counts reconnects, restarts the line timing.
  void noteConnected();
  // Waits out the silence before the next frame (a real-time thread spins its last part).
  void keepGap();
  // The late-reply guard: when a transaction with this slave failed less than
  // late_reply_guard ago and this is a different request, drops what `fd` brings until it
  // has been quiet that long.
  void settleLine(int fd, const EncodedRequest& request);
  // The guard's decision, apart from the medium (an in-memory line waits on its own clock):
  // until when the line must be quiet before `request` goes (none: it may go now); after
  // that wait, lineSettled(request).
  std::optional<std::chrono::steady_clock::time_point> guardUntil(const EncodedRequest& request);
  void lineSettled(const EncodedRequest& request);
  // The clock of the line's timing (the guard, the last activity): the steady clock; a
  // simulated medium gives its own.
  virtual std::chrono::steady_clock::time_point lineNow() const {
    return std::chrono::steady_clock::now();
  }
  void addStaleBytes(uint64_t n);
  bool retrying() const { return retrying_; }  // the attempt running is a retry
  // The failure a reader status means ("gateway" or the port in `medium` messages).
  Result readFailure(const Request& request, ReadStatus status, const Bytes& partial, int error,
                     const std::string& medium) const;
  // The RTU reply to `request` on `fd` (a serial port, or a transparent gateway's socket): its
  // first byte within the response timeout, each next one within `byte_timeout`, read by its
  // announced length and decoded (frame.h's checks); failures name `medium`.
  Result readRtuReply(int fd, const EncodedRequest& request, double byte_timeout,
                      const std::string& medium);
  // readFrame (fd_io.h), and what it read to the wire observer.
  ReadStatus readObserved(int fd, double first, double between,
                          const std::function<long(const Bytes&)>& length_of, size_t shortest,
                          size_t max_length, Bytes* out, int* error);
  bool observingWire() const { return static_cast<bool>(wire_observer_); }
  // WireEvent::cpu now (a clock call: only while observed).
  double wireCpuSeconds() const;
  // A request takes the lateness of the gap's last sleep.
  void noteWire(bool outgoing, std::chrono::steady_clock::time_point first,
                std::chrono::steady_clock::time_point last, const Bytes& frame, double cpu);

  LinkConfig config_;
  LinkTarget target_;
  double reply_delay_[256] = {};
  std::chrono::steady_clock::time_point last_activity_{};

 private:
  Result runAttempt(const EncodedRequest& request);
  Result runBroadcast(const EncodedRequest& request);
  void awaitQuietLine(int fd, std::chrono::steady_clock::time_point until);
  // Drops the failed transactions whose late reply can no longer come (their guard ran out).
  void forgetSettled(std::chrono::steady_clock::time_point now);
  double worstSeconds(const EncodedRequest& request) const;  // worstTransactionSeconds, encoded
  // One attempt of `request` on the line: the gap, the frame, the response timeout and the
  // longest reply ended by one byte timeout (a broadcast: the gap and the frame).
  double attemptWorstSeconds(const EncodedRequest& request) const;
  // How much of a gap a real-time thread spins: 1.5 x the sleeps' lateness + 10 us, at most
  // kMaxGapSpin.
  std::chrono::steady_clock::duration gapSpinMargin() const;
  void account(const Result& result, double latency);  // per transaction
  void countAttempt(const Result& result);             // per attempt: failures by kind

  mutable std::mutex stats_mutex_;
  LinkStats stats_;
  bool ever_connected_ = false;
  struct Unsettled {  // a failed transaction whose reply may still come
    // When its own reply would have timed out (not earlier, if it ended on another frame).
    std::chrono::steady_clock::time_point failed_at;
    Bytes frame;
  };
  std::map<uint8_t, Unsettled> unsettled_;  // by slave
  Bytes reply_buffer_;                      // readRtuReply's, reused (bus thread)
  // The failed transaction whose late reply holds `request` (F90), or nullptr: none with its
  // slave, or `request` may take that reply (a `retry` of it, or a new read with its frame).
  const Unsettled* holding(const EncodedRequest& request, bool retry) const;
  bool retrying_ = false;  // the attempt running is a retry (guardUntil)
  // When the attempt running was through the guard (its request goes after the gap from here):
  // its own reply is due by then plus the gap, the frame and the response timeout.
  std::chrono::steady_clock::time_point settled_at_{};
  WireObserver wire_observer_;
  // keepGap: how late sleeps have woken, a slow average (27 us before the first: a 50 us margin).
  static constexpr std::chrono::microseconds kMaxGapSpin{200};
  // keepGap: a rest of a gap this short is spun at any priority (a sleep costs more).
  static constexpr std::chrono::microseconds kBriefGap{20};
  std::chrono::steady_clock::duration wake_lateness_{std::chrono::microseconds(27)};
  std::chrono::steady_clock::duration spun_{};        // keepGap's spinning, in all
  std::chrono::steady_clock::duration gap_late_{};    // its last sleep's lateness, for noteWire
  std::chrono::steady_clock::duration guard_wait_{};  // awaitQuietLine's last wait, for noteWire
  // When readObserved returned the last byte of a whole frame, for the attempt's end.
  std::optional<std::chrono::steady_clock::time_point> heard_at_;
};

}  // namespace modbus_rtu_driver
