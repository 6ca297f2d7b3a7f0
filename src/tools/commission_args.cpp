// Command line of modbus_rtu_commission, parsed by CLI11: every value is checked against the
// manuals' ranges before anything is opened or sent, and each refusal names the option and its
// range. CLI11 splits the words into the command, its options and its positional values and
// runs the checks that need nothing else; the checks that depend on the command or on another
// option (the board type's address range, --to after --from, the PDU's limits) follow.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <map>
#include <sstream>

#include "modbus_rtu_driver/core/config/device_types/lc_relay8.h"
#include "modbus_rtu_driver/core/config/device_types/ld58a08.h"
#include "modbus_rtu_driver/devices/yespeed_pdu.h"
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

// CLI11 checks of one option's value on its own; CLI11 puts the option's name in front.
CLI::Validator intRange(long lo, long hi) {
  return CLI::Validator([lo, hi](std::string& text) { return outsideInts(text, lo, hi); },
                        std::to_string(lo) + "-" + std::to_string(hi));
}

CLI::Validator secondsRange(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        double v = 0;
        if (toDouble(text, &v) && v >= lo && v <= hi) return "";
        return "'" + text + "' is outside " + rangeText(lo, hi) + " s";
      },
      rangeText(lo, hi) + " s");
}

const CLI::Validator kBaud(
    [](std::string& text) -> std::string {
      std::string problem = outsideInts(text, 1200, 115200);
      if (!problem.empty()) return problem;
      long v = 0;
      toLong(text, &v);
      if (!isStandardBaud(static_cast<int>(v)))
        return "'" + text + "' is not one of " + standardBaudList();
      return "";
    },
    "1200-115200");

const CLI::Validator kParity(
    [](std::string& text) -> std::string {
      Parity p;
      return parseParity(text, &p) ? "" : "'" + text + "' is not none, even or odd";
    },
    "none|even|odd");

const CLI::Validator kBaudList(
    [](std::string& text) -> std::string {
      for (const std::string& b : splitList(text == "all" ? standardBaudList() : text)) {
        long v = 0;
        if (!toLong(b, &v) || !isStandardBaud(static_cast<int>(v)))
          return "'" + b + "' is not one of " + standardBaudList() + " (or all)";
      }
      return "";
    },
    "LIST|all");

const CLI::Validator kParityList(
    [](std::string& text) -> std::string {
      for (const std::string& p : splitList(text == "all" ? "none,even,odd" : text)) {
        Parity parity;
        if (!parseParity(p, &parity)) return "'" + p + "' is not none, even or odd (or all)";
      }
      return "";
    },
    "LIST|all");

// Every word of the command line lands here as text; the checks above and below turn it into
// a CommissionCommand.
struct Words {
  std::string port, baud, parity, timeout;
  std::string type, address, from, to, addresses, bauds, parities, interval, count;
  std::array<std::string, 3> limits;
  std::string value, table, start, table_count;
  std::vector<std::string> values;
};

const char* const kLimitOptions[3] = {"--over-voltage", "--under-voltage", "--over-current"};

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
    app.add_option("--baud", w.baud, "line speed (default 9600)")->type_name("B")->check(kBaud);
    app.add_option("--parity", w.parity, "line parity (default none)")
        ->type_name("P")
        ->check(kParity);
    app.add_option("--timeout", w.timeout, "wait for a reply (see below)")
        ->type_name("S")
        ->check(secondsRange(0.005, 10));
    app.add_flag("--json", "results as one JSON object per line");
    app.add_flag("--yes", "no confirmation questions");

    CLI::App* scan = app.add_subcommand(
        "scan", "harmless reads at every address and line setting; names what answers");
    scan->add_option("--from", w.from, "first address (default 1)")
        ->type_name("A")
        ->check(intRange(1, 255));
    scan->add_option("--to", w.to, "last address, --from-255 (default 255)")->type_name("B");
    scan->add_option("--addresses", w.addresses, "instead of --from/--to: e.g. 1-5,255")
        ->type_name("LIST");
    scan->add_option("--bauds", w.bauds, "e.g. 9600,19200 or all (default --baud)")
        ->check(kBaudList);
    scan->add_option("--parities", w.parities, "none,even,odd or all (default --parity)")
        ->check(kParityList);
    scan->add_flag("--first", "stop at the first device found");

    CLI::App* info = app.add_subcommand("info", "type and settings of the device at --address");
    addAddress(info);

    struct Setting {
      const char* get;
      const char* set;
      const char* what;
      const char* value;
      const char* range;
    };
    const Setting settings[] = {
        {"get-address", "set-address", "the board's address", "NEW",
         "ld58a08 1-248, lc_relay8 1-255; without --address through 0xFF / 0: board alone on "
         "the bus"},
        {"get-baud", "set-baud", "the stored baud rate", "BAUD",
         "a rate or a code: ld58a08 0-7 (1200-115200), lc_relay8 2-4 (4800, 9600, 19200)"},
        {"get-parity", "set-parity", "the stored parity (ld58a08)", "none|even|odd",
         "none, even or odd"},
        {"get-return-delay", "set-return-delay", "the wait before answering (ld58a08)", "MS",
         "0-1000 ms in steps of 40"},
        {"get-save", "set-save", "the power-down save of the PWM settings (ld58a08)", "on|off",
         "on or off"},
    };
    for (const Setting& s : settings) {
      addTyped(app.add_subcommand(s.get, std::string("read ") + s.what));
      CLI::App* set = app.add_subcommand(s.set, std::string("change ") + s.what + ": " + s.range);
      addTyped(set);
      set->add_option("value", w.value, s.range)->type_name(s.value);
    }
    addTyped(app.add_subcommand("factory-reset",
                                "ld58a08 factory settings (through 0xFF without --address)"));

    addLimitsType(
        addAddress(app.add_subcommand("get-limits", "the PDU's limits (yespeed_pdu)"), "1-247"));
    CLI::App* set_limits = app.add_subcommand(
        "set-limits", "change the PDU's limits; those not given stay (yespeed_pdu)");
    addLimitsType(addAddress(set_limits, "1-247"));
    const char* limit_help[3] = {"V, in 0.1 V", "V, in 0.1 V", "A, in 0.01 A"};
    for (size_t i = 0; i < 3; ++i)
      set_limits->add_option(kLimitOptions[i], w.limits[i], limit_help[i])
          ->type_name(YespeedPdu::kLimitUnits[i]);

    CLI::App* read = app.add_subcommand("read", "one request: COUNT values from START");
    addTableCount(addTable(read));
    CLI::App* write = app.add_subcommand(
        "write", "FC05/FC06 for one value, FC15/FC16 for more (--multiple: always)");
    addTable(write)
        ->add_option("values", w.values, "0 or 1 (coils), 0-65535 (holding)")
        ->type_name("VALUE...")
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    write->add_flag("--multiple", "FC15/FC16 even for one value");
    CLI::App* watch =
        app.add_subcommand("watch", "polls; prints a line only when something changed");
    addTableCount(addTable(watch));
    watch->add_option("--interval", w.interval, "s between polls (default 0.5)")
        ->type_name("S")
        ->check(secondsRange(0.01, 3600));
    watch->add_option("--count", w.count, "polls, then stop (default: until Ctrl-C)")
        ->type_name("N")
        ->check(intRange(1, 100000000));
    for (CLI::App* command : app.get_subcommands({}))
      command->footer(
          "\n(modbus_rtu_commission --help: every command, the boards' ranges, "
          "the scan's duration, exit codes)");
    app.footer(commissionHelpDetails());
  }

  CLI::App* addAddress(CLI::App* command, const std::string& range = "1-255") {
    command->add_option("--address", w.address, "the device's address (" + range + ")")
        ->type_name("A");
    return command;
  }
  void addTyped(CLI::App* command) {
    command->add_option("--type", w.type, "ld58a08 or lc_relay8")->type_name("T");
    addAddress(command, "ld58a08 1-248, lc_relay8 1-255");
  }
  void addLimitsType(CLI::App* command) {
    command->add_option("--type", w.type, "yespeed_pdu (the only one)")->type_name("T");
  }
  // The positional COUNT is named "table-count", not "count": watch also has the option
  // --count (polls), and CLI11 2.4 (Debian 13) refuses a positional whose name equals another
  // option's long name (OptionAlreadyAdded at start), where CLI11 2.1 (Debian 12) let it pass.
  static constexpr const char* kTableCount = "table-count";
  void addTableCount(CLI::App* command) {
    command->add_option(kTableCount, w.table_count, "how many (default 1)")->type_name("COUNT");
  }
  CLI::App* addTable(CLI::App* command) {
    addAddress(command);
    command->add_option("table", w.table, "coils, discrete-inputs, holding or input-registers")
        ->type_name("TABLE");
    command->add_option("start", w.start, "first address in the table (0-65535)")
        ->type_name("START");
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
  if (p.top.count("--baud")) c.link.baud = intIn("--baud", p.w.baud, 1200, 115200);
  if (p.top.count("--parity")) parseParity(p.w.parity, &c.link.parity);
  c.link.retries = 0;
  // Scans try many silent addresses: wait little. Other commands wait out an LD58A08's return
  // delay (up to 1000 ms) too.
  const double wire = 30.0 * bitsPerCharacter(c.link) / c.link.baud;
  c.link.response_timeout = (c.command == "scan" ? 0.05 : 1.05) + wire;
  if (p.top.count("--timeout")) toDouble(p.w.timeout, &c.link.response_timeout);
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
    const int from = p.has("--from") ? intIn("--from", w.from, 1, 255) : 1;
    const int to = p.has("--to") ? intIn("--to", w.to, from, 255) : 255;
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
  for (const std::string& name : splitList(parities == "all" ? "none,even,odd" : parities)) {
    Parity parity;
    parseParity(name, &parity);
    c.parities.push_back(parity);
  }
  if (c.addresses.empty() || c.bauds.empty() || c.parities.empty())
    bad("--addresses / --bauds / --parities: empty list");
  c.first_only = p.has("--first");
}

// A baud rate or a code, as the board's own code.
int baudCode(const std::string& text, bool lc) {
  const int lo = lc ? 2 : 0, hi = lc ? 4 : 7;
  long v = -1;
  if (toLong(text, &v)) {
    if (v >= lo && v <= hi) return static_cast<int>(v);
    for (int code = lo; code <= hi; ++code)
      if (baudOfCode(code) == v) return code;
  }
  bad("baud: '" + text + "' is neither a code " + std::to_string(lo) + "-" + std::to_string(hi) +
      " nor one of " + (lc ? "4800, 9600, 19200" : standardBaudList()) + " (" +
      (lc ? kLcRelay8Type.name : kLd58a08Type.name) + ")");
}

// The settings commands: --type (ld58a08 unless the command fits both boards), --address and
// the new value in the board's units.
void parseDevice(const Parsed& p, CommissionCommand& c) {
  const std::string& cmd = c.command;
  const bool both_boards =
      cmd == "get-address" || cmd == "set-address" || cmd == "get-baud" || cmd == "set-baud";
  const std::string ld = kLd58a08Type.name, lc_type = kLcRelay8Type.name;
  if (p.has("--type")) {
    c.type = p.w.type;
    if (c.type != ld && c.type != lc_type)
      bad("--type: '" + c.type + "' is not " + ld + " or " + lc_type);
    if (!both_boards && c.type != ld)
      bad("--type: " + cmd + " is an ld58a08 command; the LC relay board has no such setting");
  } else if (both_boards) {
    bad("--type: missing (" + ld + " or " + lc_type + ")");
  } else {
    c.type = ld;
  }
  const bool lc = c.type == lc_type;
  const int max_address = lc ? kLcRelay8Type.max_address : kLd58a08Type.max_address;
  if (p.has("--address")) c.address = intIn("--address", p.w.address, 1, max_address);
  const bool address_optional =
      cmd == "get-address" || cmd == "set-address" || cmd == "factory-reset";
  if (c.address < 0 && !address_optional)
    bad("--address: missing (1-" + std::to_string(max_address) + ")");
  if (cmd.compare(0, 4, "set-") != 0) return;
  if (!p.has("value")) bad("value: missing (see --help)");
  const std::string& v = p.w.value;
  if (cmd == "set-address") {
    c.new_value = intIn("new address", v, 1, max_address);
  } else if (cmd == "set-baud") {
    c.new_value = baudCode(v, lc);
  } else if (cmd == "set-parity") {
    Parity parity;
    if (!parseParity(v, &parity)) bad("parity: '" + v + "' is not none, even or odd");
    c.new_value = parity == Parity::kEven ? 1 : parity == Parity::kOdd ? 2 : 0;
  } else if (cmd == "set-return-delay") {
    const int ms = intIn("return delay", v, 0, 1000);
    if (ms % 40) bad("return delay: " + v + " ms is not a multiple of 40 ms (0-1000)");
    c.new_value = ms / 40;
  } else if (cmd == "set-save") {
    if (v != "on" && v != "off" && v != "1" && v != "0")
      bad("power-down save: '" + v + "' is not on or off");
    c.new_value = v == "on" || v == "1";
  }
}

// The PDU's field names as the tool's options: "over_voltage: ..." -> "--over-voltage: ...".
std::string asOptions(std::string message) {
  for (const char* field : YespeedPdu::kLimitNames) {
    std::string option = std::string("--") + field;
    std::replace(option.begin(), option.end(), '_', '-');
    for (size_t at = message.find(field); at != std::string::npos;
         at = message.find(field, at + option.size())) {
      if (at >= 2 && message.compare(at - 2, 2, "--") == 0) continue;
      message.replace(at, std::string(field).size(), option);
    }
  }
  return message;
}

// get-limits / set-limits (Yespeed PDU). Each limit given is converted to the register value
// that would be written and checked there (the manual's rules, on integers); with all three the
// rule between them too. With fewer, the others are the PDU's own, and the rules are checked
// on the merged set once they are read.
void parseLimits(const Parsed& p, CommissionCommand& c) {
  c.type = kYespeedPduType.name;
  if (p.has("--type") && p.w.type != c.type)
    bad("--type: " + c.command + " is a " + c.type + " command; '" + p.w.type + "' has no limits");
  const int max_address = kYespeedPduType.max_address;
  if (!p.has("--address")) bad("--address: missing (1-" + std::to_string(max_address) + ")");
  c.address = intIn("--address", p.w.address, 1, max_address);
  if (c.command == "get-limits") return;
  bool all = true;
  for (size_t i = 0; i < 3; ++i) {
    const std::string option = kLimitOptions[i];
    if (!p.has(option)) {
      all = false;
      continue;
    }
    const std::string& text = p.w.limits[i];
    double v = 0;
    if (!toDouble(text, &v))
      bad(option + ": '" + text + "' is not a number (" + YespeedPdu::kLimitUnits[i] + ")");
    uint16_t reg = 0;
    const std::string problem = YespeedPdu::limitToRegister(i, v, &reg, option);
    if (!problem.empty()) bad(problem);
    c.limits[i] = reg;
  }
  if (c.limits[0] < 0 && c.limits[1] < 0 && c.limits[2] < 0)
    bad("set-limits: give at least one of --over-voltage V, --under-voltage V, --over-current A "
        "(the others stay as the PDU holds them)");
  if (all) {
    const std::string problem = YespeedPdu::checkLimitRegisters(
        {static_cast<uint16_t>(c.limits[0]), static_cast<uint16_t>(c.limits[1]),
         static_cast<uint16_t>(c.limits[2])});
    if (!problem.empty()) bad(asOptions(problem));
  }
}

// info, read, write, watch: any device type, so any address a board can have.
void parseAnyAddress(const Parsed& p, CommissionCommand& c) {
  if (!p.has("--address")) bad("--address: missing (1-255)");
  c.address = intIn("--address", p.w.address, 1, 255);
}

void parseTable(const Parsed& p, CommissionCommand& c) {
  const Words& w = p.w;
  parseAnyAddress(p, c);
  if (!p.has("table")) bad("table: missing (coils, discrete-inputs, holding or input-registers)");
  c.table = w.table;
  const bool bits = c.table == "coils" || c.table == "discrete-inputs";
  if (!bits && c.table != "holding" && c.table != "input-registers")
    bad("table: '" + c.table + "' is not coils, discrete-inputs, holding or input-registers");
  if (!p.has("start")) bad("start: missing (0-65535)");
  c.start = intIn("start", w.start, 0, 65535);
  if (c.command == "write") {
    if (c.table != "coils" && c.table != "holding")
      bad("table: " + c.table + " cannot be written (coils or holding)");
    if (w.values.empty()) bad("value: missing (" + std::string(bits ? "0 or 1" : "0-65535") + ")");
    const size_t max = bits ? kMaxWriteBits : kMaxWriteRegisters;
    if (w.values.size() > max)
      bad("value: " + std::to_string(w.values.size()) + " values, at most " + std::to_string(max));
    for (const std::string& value : w.values)
      c.values.push_back(static_cast<uint16_t>(intIn("value", value, 0, bits ? 1 : 65535)));
    c.count = static_cast<int>(c.values.size());
    c.multiple = p.has("--multiple");
  } else {
    const int max = bits ? kMaxReadBits : kMaxReadRegisters;
    if (p.has(Cli::kTableCount)) c.count = intIn("count", w.table_count, 1, max);
  }
  if (c.start + c.count > 65536)
    bad("start: " + std::to_string(c.start) + " + " + std::to_string(c.count) + " passes 65535");
  if (c.command == "watch") {
    if (p.has("--interval")) toDouble(w.interval, &c.interval);
    if (p.has("--count")) c.polls = intIn("--count", w.count, 1, 100000000);
  }
}

// CLI11's own refusals, in this tool's words where they have a usual form.
std::string describe(const CLI::ParseError& e) {
  std::string what = e.what();
  const size_t colon = what.find(':');
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

std::string commissionUsage() {
  return Cli().app.help();
}

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
      bad(describe(e));
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
