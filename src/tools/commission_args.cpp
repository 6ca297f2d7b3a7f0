// Command line of modbus_rtu_commission, parsed by CLI11: every value is checked against the
// manuals' ranges before anything is opened or sent, and each refusal names the option and its
// range. CLI11 splits the words into the command, its options and its positional values,
// converts each to its type and runs the checks that need nothing else (CLI::Range,
// CLI::IsMember, in this tool's words); the checks that depend on the command or on another
// option (the board type's ranges, from its class in devices/commissioning.h; --to after
// --from; a type's limits) follow, on the converted values.
// The jobs have their own files: commission_values (numbers and lists from words),
// commission_validators (CLI11's checks), commission_settings (the settings commands),
// commission_cli (the CLI11 app) and commission_parse (each command's checks).
#include <CLI/CLI.hpp>
#include <algorithm>

#include "modbus_rtu_driver/tools/commission.h"
#include "modbus_rtu_driver/tools/commission_cli.h"
#include "modbus_rtu_driver/tools/commission_parse.h"
#include "modbus_rtu_driver/tools/commission_settings.h"
#include "modbus_rtu_driver/tools/commission_values.h"

namespace modbus_rtu_driver {

namespace {

using commission_args::bad;
using commission_args::BadArgument;
using commission_args::Cli;
using commission_args::Parsed;
using commission_args::SettingCommand;
using commission_args::settingCommand;

// CLI11's own refusals, in this tool's words where they have a usual form. A positional value
// is named in messages as the command calls it ("parity", "count"), not by its CLI11 name.
std::string describe(const CLI::ParseError& e, const std::vector<std::string>& args) {
  std::string what = e.what();
  const size_t colon = what.find(':');
  if (dynamic_cast<const CLI::ValidationError*>(&e) && colon != std::string::npos) {
    const std::string name = what.substr(0, colon);
    if (name == Cli::kTableCount) return "count" + what.substr(colon);
    if (name == "value")
      for (const std::string& word : args)
        if (const SettingCommand* s = settingCommand(word))
          if (s->set && word == s->set) return s->label + what.substr(colon);
  }
  if (dynamic_cast<const CLI::ArgumentMismatch*>(&e) && what.compare(0, 2, "--") == 0 &&
      what.find("required") != std::string::npos && what.find("missing") != std::string::npos)
    return what.substr(0, colon) + ": missing value";
  return what;
}

// Words CLI11 could not place: an unknown command, an option the command does not have, or a
// value too many.
void refuseExtras(const CLI::App& top, const CLI::App* command) {
  const std::vector<std::string> extras = top.remaining(true);
  if (extras.empty()) return;
  const std::string& word = extras.front();
  if (!command && word.compare(0, 1, "-") != 0)
    bad("command: '" + word + "' is not known (see --help)");
  if (word.compare(0, 2, "--") == 0 && word.size() > 2) {
    const std::string option = word.substr(0, word.find('='));
    bad(option + ": not an option of " + (command ? command->get_name() : "the tool") +
        " (see --help)");
  }
  bad("unexpected argument '" + word + "'");
}

}  // namespace

bool parseCommission(const std::vector<std::string>& args, CommissionCommand* out,
                     std::string* error) {
  Cli cli;
  try {
    try {
      cli.app.parse(std::vector<std::string>(args.rbegin(), args.rend()));  // CLI11: reversed
    } catch (const CLI::CallForHelp&) {
      *out = CommissionCommand();
      out->help = cli.app.help();  // the command's own when one was given
      return true;
    } catch (const CLI::CallForAllHelp&) {
      *out = CommissionCommand();
      out->help = cli.app.help("", CLI::AppFormatMode::All);
      return true;
    } catch (const CLI::ParseError& e) {
      bad(describe(e, args));
    }
    const std::vector<CLI::App*> commands = cli.app.get_subcommands();
    const CLI::App* command = commands.empty() ? nullptr : commands.front();
    refuseExtras(cli.app, command);
    if (!command) bad("command: missing (see --help)");
    CommissionCommand c;
    c.json = cli.app.count("--json") != 0;
    c.yes = cli.app.count("--yes") != 0;
    c.command = command->get_name();
    const Parsed p{cli.app, *command, cli.w};
    parseLink(p, c);
    if (c.command == "scan") {
      parseScan(p, c);
    } else if (c.command == "read" || c.command == "write" || c.command == "watch") {
      parseTable(p, c);
    } else if (c.command == "get-limits" || c.command == "set-limits") {
      parseLimits(p, c);
    } else if (c.command == "info") {
      parseAnyAddress(p, c);
    } else {
      parseDevice(p, c);
    }
    *out = c;
    return true;
  } catch (const BadArgument& e) {
    *error = e.message;
    out->json = std::find(args.begin(), args.end(), "--json") != args.end();
    return false;
  }
}

}  // namespace modbus_rtu_driver
