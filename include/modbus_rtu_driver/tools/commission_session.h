// Inside modbus_rtu_commission: what each group of commands gets to work with, so the device
// and table commands also run against a scripted transport in the unit tests.
#pragma once

#include <atomic>
#include <iosfwd>
#include <string>

#include "modbus_rtu_driver/core/link/transport.h"
#include "modbus_rtu_driver/devices/commissioning.h"
#include "modbus_rtu_driver/tools/commission.h"
#include "modbus_rtu_driver/tools/commission_output.h"

namespace modbus_rtu_driver {

struct Session {
  const CommissionCommand& cmd;
  Transport& transport;  // the port at --baud / --parity
  Output& out;
  std::istream& in;
  const std::atomic<bool>& stop;

  // Asks on stderr and reads one line: "y" or "yes" confirms; anything else, EOF or an
  // interrupted read does not. --yes answers for the user.
  bool confirm(const std::string& question);
};

// Harmless reads that tell whether something answers at `address` and which type it looks like.
struct Identity {
  bool present = false;
  std::string
      type;  // a registered type's name (devices/commissioning.h), or "unknown modbus device"
  std::string note;  // why an answer was not taken as a device there
};
Identity identifyDevice(Transport& transport, uint8_t address);

// get/set-address, -baud, -parity, -return-delay, -save, factory-reset, info.
int runDeviceCommand(Session& session);
// read, write, watch.
int runTableCommand(Session& session);
// Opens its own link for every baud and parity it tries.
int runScan(const CommissionCommand& cmd, Output& out, const std::atomic<bool>& stop,
            bool err_is_terminal);

// "9600 8N1"

}  // namespace modbus_rtu_driver
