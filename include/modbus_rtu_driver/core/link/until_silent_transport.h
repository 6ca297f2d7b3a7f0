// A transport for one bus job: it passes requests on until one gets no reply at all (the link's
// retries spent), then refuses the rest of that job unsent. A device that does not answer so
// costs the bus one transaction for that job, not one per request (a write and the read that
// would confirm it): the fail-safe runs a trigger's safe write through it, so that the other
// devices' safe writes go first (docs/failsafe.md, "Timing").
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
