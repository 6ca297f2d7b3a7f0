// The transport a lasting trigger's safe write goes through (docs/failsafe.md, "Timing"): it
// passes requests on until one gets no reply at all (the link's retries spent), then refuses the
// rest of that job unsent. A device that went silent since its last answer so costs the other
// devices' safe writes one transaction, not two: the read that would tell whether its write got
// through anyway is refused here, and DeviceFailsafe runs it after the others' safe writes.
#pragma once

#include "modbus_rtu_driver/core/link/transport.h"

namespace modbus_rtu_driver {

class UntilSilentTransport : public Transport {
 public:
  explicit UntilSilentTransport(Transport& inner) : inner_(inner) {}
  Result execute(const Request& request) override;
  bool connected() const override { return inner_.connected(); }
  void awaitLineFree() override { inner_.awaitLineFree(); }
  // A request was refused unsent after the device gave no reply.
  bool refused() const { return refused_; }

 private:
  Transport& inner_;
  bool silent_ = false;
  bool refused_ = false;
};

}  // namespace modbus_rtu_driver
