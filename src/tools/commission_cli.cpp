#include "modbus_rtu_driver/tools/commission_cli.h"

#include <algorithm>

#include "modbus_rtu_driver/core/modbus/switch_words.h"
#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/tools/commission.h"
#include "modbus_rtu_driver/tools/commission_validators.h"
#include "modbus_rtu_driver/tools/commission_values.h"

namespace modbus_rtu_driver::commission_args {

// "over_voltage" -> "--over-voltage"
std::string limitOption(const std::string& name) {
  std::string option = "--" + name;
  std::replace(option.begin(), option.end(), '_', '-');
  return option;
}

// "0.1" for one decimal
std::string stepText(int decimals) {
  return decimals <= 0 ? "1" : "0." + std::string(static_cast<size_t>(decimals - 1), '0') + "1";
}

Cli::Cli() {
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.allow_extras();
  app.fallthrough();
  app.require_subcommand(0, 1);
  app.set_help_all_flag("--help-all", "help of every command");
  // The kinds of link register themselves (core/link/link_types.h): the help lists them.
  app.add_option("--port", w.port, linkTypes().formList() + " (needed; see below)")
      ->type_name("PORT");
  app.add_option("--baud", w.baud, "line speed (default 9600)")
      ->type_name("B")
      ->transform(baudRate());
  app.add_option("--parity", w.parity, "line parity (default none)")
      ->type_name("P")
      ->transform(parityOption());
  app.add_option("--timeout", w.timeout, "wait for a reply (see below)")
      ->type_name("S")
      ->check(secondsRange(0.005, 10));
  app.add_flag("--json", "results as one JSON object per line");
  app.add_flag("--yes", "no confirmation questions");

  CLI::App* scan = app.add_subcommand(
      "scan", "harmless reads at every address and line setting; names what answers");
  scan->add_option("--from", w.from, "first address (default 1)")
      ->type_name("A")
      ->transform(intRange(1, 255));
  scan->add_option("--to", w.to, "last address, --from-255 (default 255)")
      ->type_name("B")
      ->transform(intRange(1, 255));
  scan->add_option("--addresses", w.addresses, "instead of --from/--to: e.g. 1-5,255")
      ->type_name("LIST");
  scan->add_option("--bauds", w.bauds, "e.g. 9600,19200 or all (default --baud)")
      ->check(baudList());
  scan->add_option("--parities", w.parities, "none,even,odd or all (default --parity)")
      ->check(parityList());
  scan->add_flag("--first", "stop at the first device found");

  CLI::App* info = app.add_subcommand("info", "type and settings of the device at --address");
  addAddress(info);

  // The settings commands, each for the registered types that have its setting.
  for (const SettingCommand& s : kSettingCommands) {
    const std::vector<std::string> names = namesOf(typesWith(s.feature));
    const std::string types = " (" + orList(names) + ")";
    if (!s.set) {
      addTyped(app.add_subcommand(s.get, std::string(s.what) + types +
                                             (s.feature == BoardFeature::kFactoryReset
                                                  ? ", without --address through the "
                                                    "address every board takes"
                                                  : "")),
               s);
      continue;
    }
    const std::string range = rangeHelp(s);
    addTyped(app.add_subcommand(s.get, std::string("read ") + s.what + types), s);
    CLI::App* set =
        app.add_subcommand(s.set, std::string("change ") + s.what + types + ": " + range);
    addTyped(set, s);
    CLI::Option* value = set->add_option("value", w.value, range)->type_name(s.value);
    // The settings whose words are the same for every type are checked here already.
    if (s.feature == BoardFeature::kParity) value->check(parityWords());
    if (s.feature == BoardFeature::kPowerDownSave)
      value->check(refusing(CLI::Validator(
                                [](std::string& text) {
                                  return parseSwitch(text) ? std::string() : std::string("no");
                                },
                                "on|off"),
                            [](const std::string& text) {
                              return "'" + text + "' is not one of " + std::string(kSwitchWords);
                            }));
  }

  // The limits commands, for the registered types that have limits; one option per limit
  // name any of them has.
  const std::vector<CommissioningType> limited = typesWith(BoardFeature::kLimits);
  if (!limited.empty()) {
    const std::string names = " (" + orList(namesOf(limited)) + ")";
    CLI::App* get_limits = app.add_subcommand("get-limits", "the protection limits" + names);
    CLI::App* set_limits = app.add_subcommand(
        "set-limits", "change the protection limits; those not given stay" + names);
    for (CLI::App* command : {get_limits, set_limits}) addLimitsType(command);
    for (const CommissioningType& t : limited)
      for (const LimitSpec& limit : t.commissioning->limitList()) {
        const std::string option = limitOption(limit.name);
        if (set_limits->get_option_no_throw(option)) continue;
        set_limits
            ->add_option(
                option, w.limits[option],
                std::string(limit.unit) + ", in " + stepText(limit.decimals) + " " + limit.unit)
            ->type_name(limit.unit);
      }
  }

  CLI::App* read = app.add_subcommand("read", "one request: COUNT values from START");
  addTableCount(addTable(read));
  CLI::App* write = app.add_subcommand(
      "write", "FC05/FC06 for one value, FC15/FC16 for more (--multiple: always)");
  addTable(write)
      ->add_option("value", w.values, "0 or 1 (coils), 0-65535 (holding)")
      ->type_name("VALUE...")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->transform(intRange(0, 65535));
  write->add_flag("--multiple", "FC15/FC16 even for one value");
  CLI::App* watch = app.add_subcommand("watch", "polls; prints a line only when something changed");
  addTableCount(addTable(watch));
  watch->add_option("--interval", w.interval, "s between polls (default 0.5)")
      ->type_name("S")
      ->check(secondsRange(0.01, 3600));
  watch->add_option("--count", w.count, "polls, then stop (default: until Ctrl-C)")
      ->type_name("N")
      ->transform(intRange(1, 100000000));
  for (CLI::App* command : app.get_subcommands({}))
    command->footer(
        "\n(modbus_rtu_commission --help: every command, the boards' ranges, "
        "the scan's duration, exit codes)");
  app.footer(commissionHelpDetails());
}

CLI::App* Cli::addAddress(CLI::App* command, const std::string& range) {
  command->add_option("--address", w.address, "the device's address (" + range + ")")
      ->type_name("A")
      ->transform(intRange(1, 255));
  return command;
}

void Cli::addTyped(CLI::App* command, const SettingCommand& s) {
  const std::vector<CommissioningType> types = typesWith(s.feature);
  const std::string ranges = join(types, ", ", [](const CommissioningType& t) {
    return std::string(t.type->name) + " 1-" + std::to_string(t.type->max_address);
  });
  command->add_option("--type", w.type, orList(namesOf(types)))
      ->type_name("T")
      ->check(typeFor(command->get_name(), s.feature));
  addAddress(command, ranges);
}

void Cli::addLimitsType(CLI::App* command) {
  addTyped(command, SettingCommand{"", nullptr, BoardFeature::kLimits, "", "", ""});
}

void Cli::addTableCount(CLI::App* command) {
  command->add_option(kTableCount, w.table_count, "how many (default 1)")
      ->type_name("COUNT")
      ->transform(anInteger("1-" + std::to_string(kMaxReadBits) + " values of a bit table, 1-" +
                            std::to_string(kMaxReadRegisters) + " registers"));
}

CLI::App* Cli::addTable(CLI::App* command) {
  addAddress(command);
  command->add_option("table", w.table, namesIn(kTableNames))
      ->type_name("TABLE")
      ->check(tableName());
  command->add_option("start", w.start, "first address in the table (0-65535)")
      ->type_name("START")
      ->transform(intRange(0, 65535));
  return command;
}

}  // namespace modbus_rtu_driver::commission_args
