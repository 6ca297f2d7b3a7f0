// modbus_rtu_commission: find and configure boards without the vendors' Windows programs.
// ROS-free; usable without a ROS master. Parsing (with every range check) is separate from
// running, so bad values are refused before the port is even opened.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/config/link_config.h"
#include "modbus_rtu_driver/core/link/link_types.h"
#include "modbus_rtu_driver/core/modbus/types.h"

namespace modbus_rtu_driver {

enum CommissionExit {
  kExitOk = 0,
  kExitBadArguments = 2,
  kExitNotFound = 3,      // no answer
  kExitRefused = 4,       // the device answered with a Modbus exception
  kExitBusError = 5,      // CRC, I/O, port
  kExitNotConfirmed = 6,  // the user did not confirm a change
};

// s a scan waits for each answer through a Modbus TCP gateway (tcp://, the node's share) when
// no --timeout is given. The gateway answers every request itself, 0B after its own response
// timeout and retries when nothing answered on its line (the node's share: its response_timeout
// x (retries + 1), after the requests queued before). A request given up sooner stays queued in
// the gateway, and every later address waits behind it.
constexpr double kGatewayScanTimeout = 3.0;

struct CommissionCommand {
  LinkConfig link;    // --port, --baud, --parity, --timeout; no retries: say what happened
  LinkTarget target;  // --port, parsed
  bool json = false, yes = false;
  std::string command;  // scan, get-address, set-address, ...
  std::string type;     // a registered type with the command's setting (devices/commissioning.h)
  int address = -1;     // --address; -1 = not given
  // set-*: the new value in the device's own units: address, baud code, parity code (0 none,
  // 1 even, 2 odd), return delay in 40 ms steps, power-down save 0/1.
  int new_value = -1;
  // set-limits: the type's limits (devices/commissioning.h, its limitList() order) as the
  // registers take them, each already checked against its own rule; -1 = keep what the device
  // holds.
  std::vector<int> limits;
  // read / write / watch
  Table table = Table::kCoil;
  int start = 0, count = 1;
  std::vector<uint16_t> values;
  bool multiple = false;  // write: FC15/FC16 even for one value
  double interval = 0.5;  // watch: s between polls
  int polls = 0;          // watch: 0 = until interrupted
  // scan
  std::vector<int> addresses;
  std::vector<int> bauds;
  std::vector<Parity> parities;
  bool first_only = false;
  // --help / --help-all: the text to print (and nothing else to do).
  std::string help;
};

// The part of --help after the option lists: each command's words and ranges (the registered
// types', devices/commissioning.h), their factory settings and manuals, exit codes.
std::string commissionHelpDetails();
// False with a message naming the option and its allowed range; out->json then tells whether
// --json was given (for the form of the message). --help parses to a command with only `help`.
bool parseCommission(const std::vector<std::string>& args, CommissionCommand* out,
                     std::string* error);

struct CommissionIo {
  std::istream& in;               // answers to confirmation questions
  std::ostream& out;              // results (human or JSON)
  std::ostream& err;              // progress, questions, reminders, human error messages
  const std::atomic<bool>& stop;  // set by SIGINT: ends scans and watches early
  bool err_is_terminal = false;   // progress redrawn in place instead of line by line
};

// Opens the port and runs a parsed command; returns the exit code.
int runCommission(const CommissionCommand& command, const CommissionIo& io);

}  // namespace modbus_rtu_driver
