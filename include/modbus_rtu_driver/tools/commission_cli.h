// The commissioning tool's command line as CLI11 sees it: options before the command are the
// link's; every command has its own. Global options may also follow the command (fallthrough).
// Unknown words are kept as extras and refused by parseCommission with the command's name.
#pragma once

#include <CLI/CLI.hpp>
#include <map>
#include <string>
#include <vector>

#include "modbus_rtu_driver/tools/commission_settings.h"

namespace modbus_rtu_driver::commission_args {

// The command line's values, each converted by CLI11 once its check passed. The setting
// commands' value stays text: what it may be (a code or a rate, a multiple of a step) is the
// type's, known only once --type is.
struct Words {
  std::string port;
  int baud = 0, parity = 0;
  double timeout = 0;
  std::string type;
  int address = 0, from = 0, to = 0;
  std::string addresses, bauds, parities;
  double interval = 0;
  int count = 0;
  std::map<std::string, std::string> limits;  // by option: "--over-voltage" -> "260"
  std::string value, table;
  int start = 0, table_count = 0;
  std::vector<int> values;
};

// "over_voltage" -> "--over-voltage"
std::string limitOption(const std::string& name);

class Cli {
 public:
  Cli();

  CLI::App app{"Finds and configures Modbus RTU boards on a serial port; no ROS master needed.",
               "modbus_rtu_commission"};
  Words w;

  // The positional COUNT is named "table-count", not "count": watch also has the option
  // --count (polls), and CLI11 2.4 (Debian 13) refuses a positional whose name equals another
  // option's long name (OptionAlreadyAdded at start), where CLI11 2.1 (Debian 12) let it pass.
  static constexpr const char* kTableCount = "table-count";

 private:
  // Any address a board can have here; a type's narrower range is checked once --type is known.
  CLI::App* addAddress(CLI::App* command, const std::string& range = "1-255");
  void addTyped(CLI::App* command, const SettingCommand& s);
  void addLimitsType(CLI::App* command);
  void addTableCount(CLI::App* command);
  CLI::App* addTable(CLI::App* command);
};

}  // namespace modbus_rtu_driver::commission_args
