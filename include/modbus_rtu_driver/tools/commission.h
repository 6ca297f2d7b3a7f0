// modbus_rtu_commission: find and configure boards without the vendors' Windows programs.
// ROS-free; usable without a ROS master. Parsing (with every range check) is separate from
// running, so bad values are refused before the port is even opened.
#pragma once

#include <atomic>
#include <iosfwd>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/link_config.h"
#include "modbus_rtu_driver/core/transport.h"

namespace modbus_rtu_driver {

enum CommissionExit {
  kExitOk = 0,
  kExitBadArguments = 2,
  kExitNotFound = 3,      // no answer
  kExitRefused = 4,       // the device answered with a Modbus exception
  kExitBusError = 5,      // CRC, I/O, port
  kExitNotConfirmed = 6,  // the user did not confirm a change
};

struct CommissionCommand {
  LinkConfig link;
  bool json = false, yes = false;
  std::string command;  // scan, get-address, set-address, ...
  std::string type;     // ld58a08 | lc_relay8 (commands that depend on the board)
  int address = -1;     // -1 = not given
  std::string table;    // coils | discrete-inputs | holding | input-registers
  int start = 0, count = 1;
  std::vector<uint16_t> values;
  int new_value = 0;  // new address, baud code, parity code, delay units, save flag
  // scan
  int from = 1, to = 247;
  std::vector<int> bauds;
  std::vector<Parity> parities;
  bool first_only = false;
  // watch
  double interval = 0.5;
  int polls = 0;  // 0 = until interrupted
};

std::string commissionUsage();
// False with a message naming the option and its allowed range.
bool parseCommission(const std::vector<std::string>& args, CommissionCommand* out,
                     std::string* error);

// Runs a parsed command. `stop` ends long scans and watches early (SIGINT).
int runCommission(const CommissionCommand& command, std::istream& in, std::ostream& out,
                  std::ostream& err, const std::atomic<bool>& stop);

}  // namespace modbus_rtu_driver
