// One serial RTU link through libmodbus. Slaves 1-247 go through libmodbus's own API; address 0
// (broadcast, and the LC board's single-device commands) and 248-255, which libmodbus 3.1.6
// cannot address or filters out, go through modbus_send_raw_request and a reply reader of our
// own that checks the CRC. With libmodbus >= 3.1.7 its quirks are used instead.
// Between transactions the link keeps a minimum silence (t3.5 by default) and flushes stale
// input; after a failed one, before a different request to the same slave, it first waits
// until the line has been quiet for late_reply_guard, so a late reply is not taken as that
// answer.
// Requests marked not repeatable are never retried.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

#include "modbus_rtu_driver/core/frame.h"
#include "modbus_rtu_driver/core/link_config.h"
#include "modbus_rtu_driver/core/transport.h"

typedef struct _modbus modbus_t;  // NOLINT: libmodbus's own name

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
  uint64_t reconnects = 0;
  uint64_t stale_bytes = 0;  // thrown away before a request: late replies, noise
  double last_latency = 0;   // s, request sent to reply decoded, successful transactions
  double mean_latency = 0;   // s
  double max_latency = 0;    // s
};

class RtuLink : public Transport {
 public:
  explicit RtuLink(LinkConfig config);
  ~RtuLink() override;
  RtuLink(const RtuLink&) = delete;
  RtuLink& operator=(const RtuLink&) = delete;

  bool connect(std::string* error) override;
  bool connected() const override { return ctx_ != nullptr; }
  void disconnect() override;
  Result execute(const Request& request) override;
  void awaitLineFree() override {
    if (ctx_) keepGap();
  }

  // Response timeout for one request to `slave`: the configured one, raised to cover a device's
  // reply delay (the LD58A08 can wait up to 1000 ms before answering).
  void setReplyDelay(uint8_t slave, double seconds);

  const LinkConfig& config() const { return config_; }
  // Safe to call from any thread (diagnostics).
  LinkStats stats() const;
  // True when the port accepted ASYNC_LOW_LATENCY (USB adapters; ptys do not support it).
  // Any thread.
  bool lowLatency() const { return low_latency_.load(); }

 private:
  Result attempt(const Request& request);
  Result readViaLibmodbus(const Request& request);
  Result exchangeRaw(const Request& request, bool read_reply_ourselves);
  Result readReply(const Request& request);
  Result sendBroadcast(const Request& request);
  Result fromErrno(const Request& request, int error) const;
  void prepareLine(const Request& request);
  void awaitQuietLine(std::chrono::steady_clock::time_point until);
  void keepGap();
  double responseTimeout(const Request& request) const;
  void account(const Result& result, double latency);  // per transaction
  void countAttempt(const Result& result);             // per attempt: failures by kind

  LinkConfig config_;
  modbus_t* ctx_ = nullptr;
  mutable std::mutex stats_mutex_;
  LinkStats stats_;
  std::atomic<bool> low_latency_{false};  // read by the diagnostics thread
  bool ever_connected_ = false;
  struct Unsettled {  // a failed transaction whose reply may still come
    std::chrono::steady_clock::time_point failed_at;
    Bytes frame;
  };
  std::map<uint8_t, Unsettled> unsettled_;  // by slave
  double reply_delay_[256] = {};
  std::chrono::steady_clock::time_point last_activity_{};
};

}  // namespace modbus_rtu_driver
