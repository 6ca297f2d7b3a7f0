#include "modbus_rtu_driver/failsafe/until_silent_transport.h"

namespace modbus_rtu_driver {

Result UntilSilentTransport::execute(const Request& request) {
  if (silent_) {
    refused_ = true;
    // Counted as the silence it follows: the caller reads it as "no reply" (not confirmed).
    return Result::failure(ErrorKind::kTimeout,
                           "not sent yet: read after the other devices' safe writes");
  }
  Result r = inner_.execute(request);
  if (r.error == ErrorKind::kTimeout) silent_ = true;
  return r;
}

}  // namespace modbus_rtu_driver
