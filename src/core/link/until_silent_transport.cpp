#include "modbus_rtu_driver/core/link/until_silent_transport.h"

namespace modbus_rtu_driver {

Result UntilSilentTransport::execute(const Request& request) {
  if (silent_) {
    refused_ = true;
    // Counted as the silence it follows: the caller reads it as "no reply" (not confirmed).
    return Result::failure(ErrorKind::kTimeout, request.describe() +
                                                    ": not sent: the device gave no reply to "
                                                    "this job's request before");
  }
  Result r = inner_.execute(request);
  if (r.error == ErrorKind::kTimeout) silent_ = true;
  return r;
}

}  // namespace modbus_rtu_driver
