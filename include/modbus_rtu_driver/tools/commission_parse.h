// The commissioning tool's commands, each from its words as CLI11 converted them: the checks
// that depend on the command or on another option (the board type's ranges, from its class in
// devices/commissioning.h; --to after --from; a type's limits). A refusal throws BadArgument.
#pragma once

#include "modbus_rtu_driver/tools/commission.h"
#include "modbus_rtu_driver/tools/commission_cli.h"

namespace modbus_rtu_driver::commission_args {

// The command's words: `app` is the command's own (sub)app, `top` the whole command line.
struct Parsed {
  const CLI::App& top;
  const CLI::App& app;
  const Words& w;
  bool has(const std::string& option) const { return app.count(option) != 0; }
};

// --port, --baud, --parity, --timeout (every command).
void parseLink(const Parsed& p, CommissionCommand& c);
// scan: --from/--to or --addresses, --bauds, --parities.
void parseScan(const Parsed& p, CommissionCommand& c);
// The settings commands: --type (needed only when more than one registered type has the
// setting), --address in the type's range, and the new value in the board's units.
void parseDevice(const Parsed& p, CommissionCommand& c);
// get-limits / set-limits. Each limit given is converted to the register value that would be
// written and checked there (the manual's rules, on integers); with all of them the rules
// between them too. With fewer, the others are the device's own, and the rules are checked on
// the merged set once they are read.
void parseLimits(const Parsed& p, CommissionCommand& c);
// info, read, write, watch: any device type, so any address a board can have.
void parseAnyAddress(const Parsed& p, CommissionCommand& c);
// read, write, watch: the table, START, COUNT or the values.
void parseTable(const Parsed& p, CommissionCommand& c);

}  // namespace modbus_rtu_driver::commission_args
