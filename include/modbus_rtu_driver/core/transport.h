// The one thing device code talks to: run a Modbus transaction, get the outcome.
// Implemented by RtuLink (libmodbus on a serial port) and by the unit tests' ScriptedTransport.
#pragma once

#include "modbus_rtu_driver/core/types.h"

namespace modbus_rtu_driver {

class Transport {
 public:
  virtual ~Transport() = default;
  // Runs one request (with the link's retries). Broadcasts return success once sent.
  virtual Result execute(const Request& request) = 0;
};

}  // namespace modbus_rtu_driver
