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
#include <string>

#include "modbus_rtu_driver/core/link.h"

typedef struct _modbus modbus_t;  // NOLINT: libmodbus's own name

namespace modbus_rtu_driver {

class RtuLink : public Link {
 public:
  explicit RtuLink(LinkConfig config) : Link(std::move(config)) {}
  ~RtuLink() override;

  bool connect(std::string* error) override;
  bool connected() const override { return ctx_ != nullptr; }
  void disconnect() override;
  PortKind kind() const override { return PortKind::kSerial; }
  // True when the port accepted ASYNC_LOW_LATENCY (USB adapters; ptys do not support it).
  // Any thread.
  bool lowLatency() const override { return low_latency_.load(); }

 protected:
  Result attempt(const Request& request) override;
  Result sendBroadcast(const Request& request) override;

 private:
  Result readViaLibmodbus(const Request& request);
  Result exchangeRaw(const Request& request, bool read_reply_ourselves);
  Result readReply(const Request& request);
  Result fromErrno(const Request& request, int error) const;
  void prepareLine(const Request& request);

  modbus_t* ctx_ = nullptr;
  std::atomic<bool> low_latency_{false};  // read by the diagnostics thread
};

}  // namespace modbus_rtu_driver
