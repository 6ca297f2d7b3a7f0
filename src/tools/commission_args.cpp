// Command line of modbus_rtu_commission, parsed by CLI11: every value is checked against the
// manuals' ranges before anything is opened or sent, and each refusal names the option and its
// range. CLI11 splits the words into the command, its options and its positional values,
// converts each to its type and runs the checks that need nothing else (CLI::Range,
// CLI::IsMember, in this tool's words); the checks that depend on the command or on another
// option (the board type's ranges, from its class in devices/commissioning.h; --to after
// --from; a type's limits) follow, on the converted values.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <functional>
#include <map>
#include <sstream>

#include "modbus_rtu_driver/core/modbus/switch_words.h"
#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/devices/commissioning.h"
#include "modbus_rtu_driver/tools/commission.h"
#include "modbus_rtu_driver/tools/commission_session.h"

namespace modbus_rtu_driver {

namespace {

struct BadArgument {
  std::string message;
};
[[noreturn]] void bad(const std::string& message) {
  throw BadArgument{message};
}

// Decimal, or hexadecimal with 0x; the whole text must be the number.
bool toLong(const std::string& text, long* out) {
  const bool hex = text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X');
  const std::string digits = hex ? text.substr(2) : text;
  if (digits.empty() || digits.size() > 9) return false;
  for (size_t i = 0; i < digits.size(); ++i) {
    const auto c = static_cast<unsigned char>(digits[i]);
    const bool sign = i == 0 && c == '-' && !hex && digits.size() > 1;
    if (!(hex ? std::isxdigit(c) : std::isdigit(c)) && !sign) return false;
  }
  *out = std::stol(digits, nullptr, hex ? 16 : 10);
  return true;
}

// "'text' is outside lo-hi", or "" when text is an integer in lo-hi.
std::string outsideInts(const std::string& text, long lo, long hi) {
  long v = 0;
  if (toLong(text, &v) && v >= lo && v <= hi) return "";
  return "'" + text + "' is outside " + std::to_string(lo) + "-" + std::to_string(hi);
}

int intIn(const std::string& what, const std::string& text, int lo, int hi) {
  const std::string problem = outsideInts(text, lo, hi);
  if (!problem.empty()) bad(what + ": " + problem);
  long v = 0;
  toLong(text, &v);
  return static_cast<int>(v);
}

// The same check on a value CLI11 already converted.
void checkIn(const std::string& what, int value, int lo, int hi) {
  if (value < lo || value > hi)
    bad(what + ": '" + std::to_string(value) + "' is outside " + std::to_string(lo) + "-" +
        std::to_string(hi));
}

bool toDouble(const std::string& text, double* out) {
  std::istringstream in(text);
  char rest = 0;
  return (in >> *out) && !(in >> rest);
}

std::string rangeText(double lo, double hi) {
  std::ostringstream range;
  range << lo << "-" << hi;
  return range.str();
}

// "a, b,c" -> {"a", "b", "c"}
std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  std::istringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    const size_t first = item.find_first_not_of(' '), last = item.find_last_not_of(' ');
    items.push_back(first == std::string::npos ? "" : item.substr(first, last - first + 1));
  }
  return items;
}

// "a, b or c"
std::string orList(const std::vector<std::string>& items) {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i)
    out += (i == 0 ? "" : i + 1 == items.size() ? " or " : ", ") + items[i];
  return out;
}

// CLI11's checks of one option's value on its own; CLI11 puts the option's name in front. The
// check is CLI11's (CLI::Range, CLI::IsMember); the refusal is in this tool's words.
using Message = std::function<std::string(const std::string&)>;
CLI::Validator refusing(const CLI::Validator& check, const Message& message) {
  const std::string description = check.get_description();
  return CLI::Validator(
      [check, message](std::string& text) {
        std::string copy = text;
        return check(copy).empty() ? std::string() : message(text);
      },
      description);
}

// An integer in lo-hi, decimal or 0x-hex, rewritten as decimal for CLI11 to convert (so "010"
// is ten with every CLI11 version, not octal).
CLI::Validator intRange(long lo, long hi) {
  const CLI::Range range(lo, hi);
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        long v = 0;
        std::string decimal;
        if (toLong(text, &v)) decimal = std::to_string(v);
        if (decimal.empty() || !range(decimal).empty())
          return "'" + text + "' is outside " + std::to_string(lo) + "-" + std::to_string(hi);
        text = decimal;
        return "";
      },
      std::to_string(lo) + "-" + std::to_string(hi));
}

// An integer whose range depends on another value (COUNT: on the table), checked after parsing.
CLI::Validator anInteger(const std::string& range) {
  return CLI::Validator(
      [range](std::string& text) -> std::string {
        long v = 0;
        if (!toLong(text, &v)) return "'" + text + "' is not a number (" + range + ")";
        text = std::to_string(v);
        return "";
      },
      "N");
}

CLI::Validator secondsRange(double lo, double hi) {
  const CLI::Range range(lo, hi);
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        double v = 0;
        std::string copy = text;
        if (toDouble(text, &v) && range(copy).empty()) return "";
        return "'" + text + "' is outside " + rangeText(lo, hi) + " s";
      },
      rangeText(lo, hi) + " s");
}

// A standard rate (core/config/link_config.h), checked as an integer first.
CLI::Validator baudRate() {
  const CLI::Validator number = intRange(1200, 115200);
  const CLI::Validator standard = refusing(
      CLI::IsMember(std::vector<int>(std::begin(kStandardBauds), std::end(kStandardBauds))),
      [](const std::string& text) { return "'" + text + "' is not one of " + standardBaudList(); });
  return CLI::Validator(
      [number, standard](std::string& text) {
        std::string problem = number(text);
        return problem.empty() ? standard(text) : problem;
      },
      "1200-115200");
}

// A parity by its name (parseParity's check: a letter is refused with the name to write).
CLI::Validator parityWords(const std::string& suffix = "") {
  return CLI::Validator(
      [suffix](std::string& text) -> std::string {
        std::string problem;
        return parseParity(text, &problem) ? "" : problem + suffix;
      },
      "none|even|odd");
}

// The name, checked, as its Parity's number for CLI11 to convert.
CLI::Validator parityOption() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::string problem;
        const auto parity = parseParity(text, &problem);
        if (parity) text = std::to_string(static_cast<int>(*parity));
        return problem;
      },
      "none|even|odd");
}

const CLI::Validator kBaudList(
    [](std::string& text) -> std::string {
      const CLI::Validator rate = baudRate();
      for (std::string b : splitList(text == "all" ? standardBaudList() : text))
        if (!rate(b).empty())
          return "'" + b + "' is not one of " + standardBaudList() + " (or all)";
      return "";
    },
    "LIST|all");

const CLI::Validator kParityList(
    [](std::string& text) -> std::string {
      if (text == "all") return "";
      const CLI::Validator name = parityWords(" (or all)");
      for (std::string p : splitList(text)) {
        std::string problem = name(p);
        if (!problem.empty()) return problem;
      }
      return "";
    },
    "LIST|all");

// A table by its one name; a spelling of earlier versions is refused with the name to use.
const CLI::Validator kTableName(
    [](std::string& text) -> std::string {
      std::string problem;
      return parseTableName(text, &problem) ? "" : problem;
    },
    join(kTableNames, "|", [](const Named<Table>& row) { return std::string(row.name); }));

// --- the settings commands, and which registered types have them ---

struct SettingCommand {
  const char* get;
  const char* set;  // null: factory-reset (no value, no get)
  BoardFeature feature;
  const char* what;   // "the stored baud rate"
  const char* value;  // the value's name in --help: "BAUD"
  const char* label;  // the value in messages: "baud"
};

const SettingCommand kSettingCommands[] = {
    {"get-address", "set-address", BoardFeature::kAddress, "the board's address", "NEW",
     "new address"},
    {"get-baud", "set-baud", BoardFeature::kBaud, "the stored baud rate", "BAUD", "baud"},
    {"get-parity", "set-parity", BoardFeature::kParity, "the stored parity", "none|even|odd",
     "parity"},
    {"get-return-delay", "set-return-delay", BoardFeature::kReturnDelay,
     "the wait before answering", "MS", "return delay"},
    {"get-save", "set-save", BoardFeature::kPowerDownSave,
     "the power-down save of the PWM settings", "on|off", "power-down save"},
    {"factory-reset", nullptr, BoardFeature::kFactoryReset, "factory settings", "", ""},
};

const SettingCommand* settingCommand(const std::string& command) {
  for (const SettingCommand& s : kSettingCommands)
    if (command == s.get || (s.set && command == s.set)) return &s;
  return nullptr;
}

// The registered types that have `feature`, in probe order.
std::vector<CommissioningType> typesWith(BoardFeature feature) {
  std::vector<CommissioningType> out;
  for (const CommissioningType& t : commissioningTypes())
    if (t.commissioning->has(feature)) out.push_back(t);
  return out;
}

std::vector<std::string> namesOf(const std::vector<CommissioningType>& types) {
  std::vector<std::string> names;
  names.reserve(types.size());
  for (const auto& t : types) names.emplace_back(t.type->name);
  return names;
}

// "a" or "an" before a type's name, read as letters ("an ld58a08", "a yespeed_pdu").
std::string withArticle(const std::string& name) {
  const std::string vowel_sounds = "aefhilmnorsx";
  const bool an = !name.empty() && vowel_sounds.find(name[0]) != std::string::npos;
  return (an ? "an " : "a ") + name;
}

// --type of a settings command: a registered type that has the command's feature.
CLI::Validator typeFor(const std::string& command, BoardFeature feature) {
  const std::string names = orList(namesOf(typesWith(feature)));
  return CLI::Validator(
      [command, feature, names](std::string& text) -> std::string {
        const Commissioning* type = commissioningOf(text);
        if (!type) return "'" + text + "' is not " + names;
        if (!type->has(feature))
          return command + " is " + withArticle(names) + " command; " + type->title() +
                 " has no such setting";
        return "";
      },
      "");  // the option's help names them already
}

// The codes a type's baud setting takes, as rates: "4800, 9600, 19200", or "1200-115200" for
// more than three.
std::string baudsOf(const Commissioning& type, bool short_form) {
  const auto [lo, hi] = type.baudCodes();
  if (short_form && hi - lo > 2)
    return std::to_string(baudOfCode(lo)) + "-" + std::to_string(baudOfCode(hi));
  std::vector<int> bauds;
  for (int code = lo; code <= hi; ++code) bauds.push_back(baudOfCode(code));
  return join(bauds);
}

// What --help says of a settings command's value and types, from the registered classes.
std::string rangeHelp(const SettingCommand& s) {
  const std::vector<CommissioningType> types = typesWith(s.feature);
  std::string text;
  auto each = [&types, &text](const std::function<std::string(const CommissioningType&)>& f) {
    text += join(types, ", ", f);
  };
  switch (s.feature) {
    case BoardFeature::kAddress:
      each([](const CommissioningType& t) {
        return std::string(t.type->name) + " 1-" + std::to_string(t.type->max_address);
      });
      text += "; without --address ";
      text += join(types, " / ",
                   [](const CommissioningType& t) { return t.commissioning->addressPath(); });
      return text + ": board alone on the bus";
    case BoardFeature::kBaud:
      text = "a rate or a code: ";
      each([](const CommissioningType& t) {
        const auto [lo, hi] = t.commissioning->baudCodes();
        return std::string(t.type->name) + " " + std::to_string(lo) + "-" + std::to_string(hi) +
               " (" + baudsOf(*t.commissioning, true) + ")";
      });
      return text;
    case BoardFeature::kReturnDelay:
      each([](const CommissioningType& t) {
        const int step = t.commissioning->returnDelayStepMs();
        return std::string(t.type->name) + " 0-" +
               std::to_string(step * t.commissioning->returnDelayMaxUnits()) + " ms in steps of " +
               std::to_string(step);
      });
      return text;
    case BoardFeature::kParity:
      return "none, even or odd";
    case BoardFeature::kPowerDownSave:
      return "on or off";
    case BoardFeature::kFactoryReset:
    case BoardFeature::kLimits:
      break;
  }
  return text;
}

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
std::string limitOption(const std::string& name) {
  std::string option = "--" + name;
  std::replace(option.begin(), option.end(), '_', '-');
  return option;
}

// "0.1" for one decimal
std::string stepText(int decimals) {
  return decimals <= 0 ? "1" : "0." + std::string(static_cast<size_t>(decimals - 1), '0') + "1";
}

// The command line: options before the command are the link's; every command has its own.
// Global options may also follow the command (fallthrough). Unknown words are kept as extras
// and refused by parseCommission with the command's name.
struct Cli {
  CLI::App app{"Finds and configures Modbus RTU boards on a serial port; no ROS master needed.",
               "modbus_rtu_commission"};
  Words w;

  Cli() {
    app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    app.allow_extras();
    app.fallthrough();
    app.require_subcommand(0, 1);
    app.set_help_all_flag("--help-all", "help of every command");
    app.add_option(
           "--port", w.port,
           "the serial device (/dev/ttyUSB0), tcp://HOST:PORT or rtu+tcp://HOST:PORT (needed)")
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
        ->check(kBaudList);
    scan->add_option("--parities", w.parities, "none,even,odd or all (default --parity)")
        ->check(kParityList);
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
    CLI::App* watch =
        app.add_subcommand("watch", "polls; prints a line only when something changed");
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

  // Any address a board can have here; a type's narrower range is checked once --type is known.
  CLI::App* addAddress(CLI::App* command, const std::string& range = "1-255") {
    command->add_option("--address", w.address, "the device's address (" + range + ")")
        ->type_name("A")
        ->transform(intRange(1, 255));
    return command;
  }
  void addTyped(CLI::App* command, const SettingCommand& s) {
    const std::vector<CommissioningType> types = typesWith(s.feature);
    const std::string ranges = join(types, ", ", [](const CommissioningType& t) {
      return std::string(t.type->name) + " 1-" + std::to_string(t.type->max_address);
    });
    command->add_option("--type", w.type, orList(namesOf(types)))
        ->type_name("T")
        ->check(typeFor(command->get_name(), s.feature));
    addAddress(command, ranges);
  }
  void addLimitsType(CLI::App* command) {
    addTyped(command, SettingCommand{"", nullptr, BoardFeature::kLimits, "", "", ""});
  }
  // The positional COUNT is named "table-count", not "count": watch also has the option
  // --count (polls), and CLI11 2.4 (Debian 13) refuses a positional whose name equals another
  // option's long name (OptionAlreadyAdded at start), where CLI11 2.1 (Debian 12) let it pass.
  static constexpr const char* kTableCount = "table-count";
  void addTableCount(CLI::App* command) {
    command->add_option(kTableCount, w.table_count, "how many (default 1)")
        ->type_name("COUNT")
        ->transform(anInteger("1-" + std::to_string(kMaxReadBits) + " values of a bit table, 1-" +
                              std::to_string(kMaxReadRegisters) + " registers"));
  }
  CLI::App* addTable(CLI::App* command) {
    addAddress(command);
    command->add_option("table", w.table, namesIn(kTableNames))
        ->type_name("TABLE")
        ->check(kTableName);
    command->add_option("start", w.start, "first address in the table (0-65535)")
        ->type_name("START")
        ->transform(intRange(0, 65535));
    return command;
  }
};

// The command's words: `app` is the command's own (sub)app, `top` the whole command line.
struct Parsed {
  const CLI::App& top;
  const CLI::App& app;
  const Words& w;
  bool has(const std::string& option) const { return app.count(option) != 0; }
};

void parseLink(const Parsed& p, CommissionCommand& c) {
  if (!p.top.count("--port")) bad("--port: missing (the serial device, e.g. /dev/ttyUSB0)");
  c.link.port = p.w.port;
  PortAddress address;
  std::string port_error;
  if (!parsePortAddress(c.link.port, &address, &port_error)) bad("--" + port_error);
  if (p.top.count("--baud")) c.link.baud = p.w.baud;
  if (p.top.count("--parity")) c.link.parity = static_cast<Parity>(p.w.parity);
  c.link.retries = 0;
  // Scans try many silent addresses: wait little. Other commands wait out the longest return
  // delay a registered type can be set to (an LD58A08's 1000 ms) too.
  int longest_delay_ms = 0;
  for (const CommissioningType& t : typesWith(BoardFeature::kReturnDelay))
    longest_delay_ms = std::max(longest_delay_ms, t.commissioning->returnDelayStepMs() *
                                                      t.commissioning->returnDelayMaxUnits());
  const double wire = 30.0 * bitsPerCharacter(c.link) / c.link.baud;
  c.link.response_timeout = 0.05 + (c.command == "scan" ? 0 : longest_delay_ms / 1000.0) + wire;
  // Through a Modbus TCP gateway a silent address costs the gateway's time, not ours: wait for
  // its answer (kGatewayScanTimeout says why).
  if (c.command == "scan" && address.kind == PortKind::kModbusTcp)
    c.link.response_timeout = std::max(c.link.response_timeout, kGatewayScanTimeout);
  if (p.top.count("--timeout")) c.link.response_timeout = p.w.timeout;
}

void parseScan(const Parsed& p, CommissionCommand& c) {
  const Words& w = p.w;
  if (p.has("--addresses")) {
    if (p.has("--from") || p.has("--to")) bad("--addresses: give it or --from/--to, not both");
    for (const std::string& item : splitList(w.addresses)) {
      const size_t dash = item.find('-', 1);
      const int lo = intIn("--addresses", item.substr(0, dash), 1, 255);
      const int hi =
          dash == std::string::npos ? lo : intIn("--addresses", item.substr(dash + 1), lo, 255);
      for (int a = lo; a <= hi; ++a)
        if (std::find(c.addresses.begin(), c.addresses.end(), a) == c.addresses.end())
          c.addresses.push_back(a);
    }
  } else {
    const int from = p.has("--from") ? w.from : 1;
    if (p.has("--to")) checkIn("--to", w.to, from, 255);
    const int to = p.has("--to") ? w.to : 255;
    for (int a = from; a <= to; ++a) c.addresses.push_back(a);
  }
  // Each item was checked by kBaudList / kParityList.
  const std::string bauds = p.has("--bauds") ? w.bauds : std::to_string(c.link.baud);
  for (const std::string& b : splitList(bauds == "all" ? standardBaudList() : bauds)) {
    long v = 0;
    toLong(b, &v);
    c.bauds.push_back(static_cast<int>(v));
  }
  const std::string parities = p.has("--parities") ? w.parities : parityName(c.link.parity);
  if (parities == "all")
    for (const auto& row : kParityNames) c.parities.push_back(row.value);
  else
    for (const std::string& name : splitList(parities))
      c.parities.push_back(*parseParity(name, nullptr));
  if (c.addresses.empty() || c.bauds.empty() || c.parities.empty())
    bad("--addresses / --bauds / --parities: empty list");
  c.first_only = p.has("--first");
}

// A baud rate or a code, as the board's own code (the type's codes index kStandardBauds).
int baudCode(const std::string& text, const CommissioningType& t) {
  const auto [lo, hi] = t.commissioning->baudCodes();
  long v = -1;
  if (toLong(text, &v)) {
    if (v >= lo && v <= hi) return static_cast<int>(v);
    for (int code = lo; code <= hi; ++code)
      if (baudOfCode(code) == v) return code;
  }
  bad("baud: '" + text + "' is neither a code " + std::to_string(lo) + "-" + std::to_string(hi) +
      " nor one of " + baudsOf(*t.commissioning, false) + " (" + t.type->name + ")");
}

// The registered type a settings command is for: --type (needed only when more than one
// registered type has `feature`), checked against those that have it.
CommissioningType chosenType(const Parsed& p, CommissionCommand& c, BoardFeature feature) {
  const std::vector<CommissioningType> types = typesWith(feature);
  if (p.has("--type")) {
    c.type = p.w.type;  // checked by typeFor
  } else if (types.size() == 1) {
    c.type = types.front().type->name;
  } else {
    bad("--type: missing (" + orList(namesOf(types)) + ")");
  }
  const auto it = std::find_if(types.begin(), types.end(),
                               [&c](const auto& t) { return c.type == t.type->name; });
  if (it == types.end()) bad("--type: '" + c.type + "' is not " + orList(namesOf(types)));
  return *it;
}

// The settings commands: --type (needed only when more than one registered type has the
// setting), --address in the type's range, and the new value in the board's units.
void parseDevice(const Parsed& p, CommissionCommand& c) {
  const std::string& cmd = c.command;
  const SettingCommand& s = *settingCommand(cmd);
  const CommissioningType type = chosenType(p, c, s.feature);
  const int max_address = type.type->max_address;
  if (p.has("--address")) {
    c.address = p.w.address;
    checkIn("--address", c.address, 1, max_address);
  }
  // Address commands and the factory reset may go through the address every board of the
  // type takes, where it has one.
  const bool address_optional =
      (s.feature == BoardFeature::kAddress || s.feature == BoardFeature::kFactoryReset) &&
      !type.commissioning->addressPath().empty();
  if (c.address < 0 && !address_optional)
    bad("--address: missing (1-" + std::to_string(max_address) + ")");
  if (!s.set || cmd != s.set) return;
  if (!p.has("value")) bad("value: missing (see --help)");
  const std::string& v = p.w.value;
  switch (s.feature) {
    case BoardFeature::kAddress:
      c.new_value = intIn(s.label, v, 1, max_address);
      break;
    case BoardFeature::kBaud:
      c.new_value = baudCode(v, type);
      break;
    case BoardFeature::kParity:  // the name was checked by parityWords
      // The stored codes 0 none, 1 even, 2 odd are Parity's order (enum class Parity).
      c.new_value = static_cast<int>(*parseParity(v, nullptr));
      break;
    case BoardFeature::kReturnDelay: {
      // A type with a return delay has a step of at least 1 ms (a 0 would divide by zero).
      const int step = std::max(1, type.commissioning->returnDelayStepMs());
      const int max_ms = step * type.commissioning->returnDelayMaxUnits();
      const int ms = intIn(s.label, v, 0, max_ms);
      if (ms % step)
        bad(std::string(s.label) + ": " + v + " ms is not a multiple of " + std::to_string(step) +
            " ms (0-" + std::to_string(max_ms) + ")");
      c.new_value = ms / step;
      break;
    }
    case BoardFeature::kPowerDownSave:  // the word was checked by the option's validator
      c.new_value = parseSwitch(v).value_or(false);
      break;
    case BoardFeature::kFactoryReset:
    case BoardFeature::kLimits:
      break;
  }
}

// A type's limit names as the tool's options: "over_voltage: ..." -> "--over-voltage: ...".
std::string asOptions(std::string message, const std::vector<LimitSpec>& limits) {
  for (const LimitSpec& limit : limits) {
    const std::string field = limit.name, option = limitOption(field);
    for (size_t at = message.find(field); at != std::string::npos;
         at = message.find(field, at + option.size())) {
      if (at >= 2 && message.compare(at - 2, 2, "--") == 0) continue;
      message.replace(at, field.size(), option);
    }
  }
  return message;
}

// get-limits / set-limits. Each limit given is converted to the register value that would be
// written and checked there (the manual's rules, on integers); with all of them the rules
// between them too. With fewer, the others are the device's own, and the rules are checked on
// the merged set once they are read.
void parseLimits(const Parsed& p, CommissionCommand& c) {
  const CommissioningType chosen = chosenType(p, c, BoardFeature::kLimits);
  const Commissioning& type = *chosen.commissioning;
  const int max_address = chosen.type->max_address;
  if (!p.has("--address")) bad("--address: missing (1-" + std::to_string(max_address) + ")");
  c.address = p.w.address;
  checkIn("--address", c.address, 1, max_address);
  if (c.command == "get-limits") return;
  const std::vector<LimitSpec> limits = type.limitList();
  c.limits.assign(limits.size(), -1);
  bool all = true, any = false;
  const std::string given_list =
      join(limits, ", ", [](const LimitSpec& l) { return limitOption(l.name) + " " + l.unit; });
  for (size_t i = 0; i < limits.size(); ++i) {
    const std::string option = limitOption(limits[i].name);
    if (!p.has(option)) {
      all = false;
      continue;
    }
    any = true;
    const std::string& text = p.w.limits.at(option);
    double v = 0;
    if (!toDouble(text, &v))
      bad(option + ": '" + text + "' is not a number (" + limits[i].unit + ")");
    uint16_t reg = 0;
    const std::string problem = type.limitToRegister(i, v, &reg, option);
    if (!problem.empty()) bad(problem);
    c.limits[i] = reg;
  }
  // An option of another type's limits.
  for (const auto& [option, text] : p.w.limits)
    if (p.has(option) &&
        std::none_of(limits.begin(), limits.end(), [&option = option](const LimitSpec& l) {
          return limitOption(l.name) == option;
        }))
      bad(option + ": not a limit of " + c.type + " (see --help)");
  if (!any)
    bad("set-limits: give at least one of " + given_list + " (the others stay as " + type.title() +
        " holds them)");
  if (all) {
    const std::vector<uint16_t> regs(c.limits.begin(), c.limits.end());
    const std::string problem = type.checkLimits(regs);
    if (!problem.empty()) bad(asOptions(problem, limits));
  }
}

// info, read, write, watch: any device type, so any address a board can have.
void parseAnyAddress(const Parsed& p, CommissionCommand& c) {
  if (!p.has("--address")) bad("--address: missing (1-255)");
  c.address = p.w.address;  // checked by intRange(1, 255)
}

void parseTable(const Parsed& p, CommissionCommand& c) {
  const Words& w = p.w;
  parseAnyAddress(p, c);
  if (!p.has("table")) bad("table: missing (" + namesIn(kTableNames) + ")");
  c.table = *parseTableName(w.table, nullptr);  // checked by kTableName
  const bool bits = isBitTable(c.table);
  if (!p.has("start")) bad("start: missing (0-65535)");
  c.start = w.start;
  if (c.command == "write") {
    if (c.table != Table::kCoil && c.table != Table::kHoldingRegister)
      bad(std::string("table: ") + tableName(c.table) +
          " cannot be written (coil or holding_register)");
    if (w.values.empty()) bad("value: missing (" + std::string(bits ? "0 or 1" : "0-65535") + ")");
    const size_t max = bits ? kMaxWriteBits : kMaxWriteRegisters;
    if (w.values.size() > max)
      bad("value: " + std::to_string(w.values.size()) + " values, at most " + std::to_string(max));
    for (const int value : w.values) {
      checkIn("value", value, 0, bits ? 1 : 65535);
      c.values.push_back(static_cast<uint16_t>(value));
    }
    c.count = static_cast<int>(c.values.size());
    c.multiple = p.has("--multiple");
  } else if (p.has(Cli::kTableCount)) {
    c.count = w.table_count;
    checkIn("count", c.count, 1, bits ? kMaxReadBits : kMaxReadRegisters);
  }
  if (c.start + c.count > 65536)
    bad("start: " + std::to_string(c.start) + " + " + std::to_string(c.count) + " passes 65535");
  if (c.command == "watch") {
    if (p.has("--interval")) c.interval = w.interval;
    if (p.has("--count")) c.polls = w.count;
  }
}

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
