// One serial RTU link. libmodbus opens and configures the port and sends each frame (so its RS485
// / RTS direction control applies); every reply, whatever the address (0, 1-247, 248-255 that
// libmodbus 3.1.6 cannot address), is read by our own reader by its announced length, CRC and
// layout checked (fd_io, frame.h): one transaction path, the one the TCP transports share.
// Between transactions the link keeps a minimum silence (t3.5 by default) and flushes stale
// input; after a failed one, before a different request to the same slave, it first waits
// until the line has been quiet for late_reply_guard, so a late reply is not taken as that
// answer.
// Requests marked not repeatable are never retried.
#pragma once

#include <atomic>
#include <string>

#include "modbus_rtu_driver/core/link/link.h"

typedef struct _modbus modbus_t;  // NOLINT: libmodbus's own name

namespace modbus_rtu_driver {

class RtuLink : public Link {
 public:
  explicit RtuLink(LinkConfig config, LinkTarget target = {})
      : Link(std::move(config), std::move(target)) {}
  ~RtuLink() override;

  bool connect(std::string* error) override;
  bool connected() const override { return ctx_ != nullptr; }
  void disconnect() override;
  // True when the port accepted ASYNC_LOW_LATENCY (USB adapters; ptys do not support it).
  // Any thread.
  bool lowLatency() const override { return low_latency_.load(); }

 protected:
  Result attempt(const EncodedRequest& request) override;
  Result sendBroadcast(const EncodedRequest& request) override;

 private:
  Result send(const EncodedRequest& request);
  void prepareLine(const EncodedRequest& request);

  modbus_t* ctx_ = nullptr;
  std::atomic<bool> low_latency_{false};  // read by the diagnostics thread
};

}  // namespace modbus_rtu_driver
