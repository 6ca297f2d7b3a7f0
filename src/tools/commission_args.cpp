// Command line of modbus_rtu_commission: every value is checked against the manuals' ranges
// before anything is opened or sent, and each refusal names the option and its range.
#include <algorithm>
#include <cctype>
#include <map>
#include <set>
#include <sstream>

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

const char kAllBauds[] = "1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200";

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

int intIn(const std::string& what, const std::string& text, int lo, int hi) {
  long v = 0;
  if (!toLong(text, &v) || v < lo || v > hi)
    bad(what + ": '" + text + "' is outside " + std::to_string(lo) + "-" + std::to_string(hi));
  return static_cast<int>(v);
}

double secondsIn(const std::string& what, const std::string& text, double lo, double hi) {
  std::istringstream in(text);
  double v = 0;
  char rest = 0;
  if (!(in >> v) || in >> rest || !(v >= lo && v <= hi)) {
    std::ostringstream range;
    range << lo << "-" << hi;
    bad(what + ": '" + text + "' is outside " + range.str() + " s");
  }
  return v;
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

// The command line split into --options and positional words.
class Words {
 public:
  explicit Words(const std::vector<std::string>& args) {
    static const std::set<std::string> kFlags = {"json", "yes", "first", "multiple"};
    for (size_t i = 0; i < args.size(); ++i) {
      const std::string& a = args[i];
      if (a.size() < 3 || a.compare(0, 2, "--") != 0) {
        positional_.push_back(a);
        continue;
      }
      const std::string key = a.substr(2);
      if (kFlags.count(key)) {
        options_[key] = "";
      } else if (i + 1 < args.size() && args[i + 1].compare(0, 2, "--") != 0) {
        options_[key] = args[++i];
      } else {
        bad(a + ": missing value");
      }
    }
  }
  bool has(const std::string& key) const { return options_.count(key) != 0; }
  std::string get(const std::string& key) const { return has(key) ? options_.at(key) : ""; }
  // The command line without the options; [0] is the command.
  const std::vector<std::string>& positional() const { return positional_; }

  void allowOnly(const std::string& command, const std::set<std::string>& allowed) const {
    static const std::set<std::string> kGlobal = {"port",    "baud", "parity",
                                                  "timeout", "json", "yes"};
    for (const auto& kv : options_)
      if (!kGlobal.count(kv.first) && !allowed.count(kv.first))
        bad("--" + kv.first + ": not an option of " + command + " (see --help)");
  }
  const std::string& word(size_t n, const std::string& what, const std::string& hint) const {
    if (n >= positional_.size()) bad(what + ": missing (" + hint + ")");
    return positional_[n];
  }
  void atMost(size_t n) const {
    if (positional_.size() > n) bad("unexpected argument '" + positional_[n] + "'");
  }

 private:
  std::map<std::string, std::string> options_;
  std::vector<std::string> positional_;
};

const std::map<std::string, std::set<std::string>>& commandOptions() {
  static const std::set<std::string> kTyped = {"type", "address"};
  static const std::map<std::string, std::set<std::string>> kCommands = {
      {"scan", {"from", "to", "addresses", "bauds", "parities", "first"}},
      {"info", {"address"}},
      {"get-address", kTyped},
      {"set-address", kTyped},
      {"get-baud", kTyped},
      {"set-baud", kTyped},
      {"get-parity", kTyped},
      {"set-parity", kTyped},
      {"get-return-delay", kTyped},
      {"set-return-delay", kTyped},
      {"get-save", kTyped},
      {"set-save", kTyped},
      {"factory-reset", kTyped},
      {"get-limits", kTyped},
      {"set-limits", {"type", "address", "over-voltage", "under-voltage", "over-current"}},
      {"read", {"address"}},
      {"write", {"address", "multiple"}},
      {"watch", {"address", "interval", "count"}},
  };
  return kCommands;
}

void parseLink(const Words& w, CommissionCommand& c) {
  if (!w.has("port")) bad("--port: missing (the serial device, e.g. /dev/ttyUSB0)");
  c.link.port = w.get("port");
  if (w.has("baud")) {
    c.link.baud = intIn("--baud", w.get("baud"), 1200, 115200);
    if (!isStandardBaud(c.link.baud))
      bad("--baud: '" + w.get("baud") + "' is not one of " + kAllBauds);
  }
  if (w.has("parity") && !parseParity(w.get("parity"), &c.link.parity))
    bad("--parity: '" + w.get("parity") + "' is not none, even or odd");
  c.link.retries = 0;
  // Scans try many silent addresses: wait little. Other commands wait out an LD58A08's return
  // delay (up to 1000 ms) too.
  const double wire = 30.0 * bitsPerCharacter(c.link) / c.link.baud;
  c.link.response_timeout = (c.command == "scan" ? 0.05 : 1.05) + wire;
  if (w.has("timeout"))
    c.link.response_timeout = secondsIn("--timeout", w.get("timeout"), 0.005, 10);
}

void parseScan(const Words& w, CommissionCommand& c) {
  w.atMost(1);
  if (w.has("addresses")) {
    if (w.has("from") || w.has("to")) bad("--addresses: give it or --from/--to, not both");
    for (const std::string& item : splitList(w.get("addresses"))) {
      const size_t dash = item.find('-', 1);
      const int lo = intIn("--addresses", item.substr(0, dash), 1, 255);
      const int hi =
          dash == std::string::npos ? lo : intIn("--addresses", item.substr(dash + 1), lo, 255);
      for (int a = lo; a <= hi; ++a)
        if (std::find(c.addresses.begin(), c.addresses.end(), a) == c.addresses.end())
          c.addresses.push_back(a);
    }
  } else {
    const int from = w.has("from") ? intIn("--from", w.get("from"), 1, 255) : 1;
    const int to = w.has("to") ? intIn("--to", w.get("to"), from, 255) : 255;
    for (int a = from; a <= to; ++a) c.addresses.push_back(a);
  }
  const std::string bauds = w.has("bauds") ? w.get("bauds") : std::to_string(c.link.baud);
  for (const std::string& b : splitList(bauds == "all" ? kAllBauds : bauds)) {
    long v = 0;
    if (!toLong(b, &v) || !isStandardBaud(static_cast<int>(v)))
      bad("--bauds: '" + b + "' is not one of " + kAllBauds + " (or all)");
    c.bauds.push_back(static_cast<int>(v));
  }
  const std::string parities = w.has("parities") ? w.get("parities") : parityName(c.link.parity);
  for (const std::string& p : splitList(parities == "all" ? "none,even,odd" : parities)) {
    Parity parity;
    if (!parseParity(p, &parity)) bad("--parities: '" + p + "' is not none, even or odd (or all)");
    c.parities.push_back(parity);
  }
  if (c.addresses.empty() || c.bauds.empty() || c.parities.empty())
    bad("--addresses / --bauds / --parities: empty list");
  c.first_only = w.has("first");
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
      " nor one of " + (lc ? "4800, 9600, 19200" : kAllBauds) + " (" +
      (lc ? "lc_relay8" : "ld58a08") + ")");
}

// The settings commands: --type (ld58a08 unless the command fits both boards), --address and
// the new value in the board's units.
void parseDevice(const Words& w, CommissionCommand& c) {
  const std::string& cmd = c.command;
  const bool both_boards =
      cmd == "get-address" || cmd == "set-address" || cmd == "get-baud" || cmd == "set-baud";
  if (w.has("type")) {
    c.type = w.get("type");
    if (c.type != "ld58a08" && c.type != "lc_relay8")
      bad("--type: '" + c.type + "' is not ld58a08 or lc_relay8");
    if (!both_boards && c.type != "ld58a08")
      bad("--type: " + cmd + " is an ld58a08 command; the LC relay board has no such setting");
  } else if (both_boards) {
    bad("--type: missing (ld58a08 or lc_relay8)");
  } else {
    c.type = "ld58a08";
  }
  const bool lc = c.type == "lc_relay8";
  const int max_address = lc ? 255 : 248;  // LD58A08 manual: 1-248
  if (w.has("address")) c.address = intIn("--address", w.get("address"), 1, max_address);
  const bool address_optional =
      cmd == "get-address" || cmd == "set-address" || cmd == "factory-reset";
  if (c.address < 0 && !address_optional)
    bad("--address: missing (1-" + std::to_string(max_address) + ")");
  const bool setter = cmd.compare(0, 4, "set-") == 0;
  w.atMost(setter ? 2 : 1);
  if (!setter) return;
  const std::string& v = w.word(1, "value", "see --help");
  if (cmd == "set-address") {
    c.new_value = intIn("new address", v, 1, max_address);
  } else if (cmd == "set-baud") {
    c.new_value = baudCode(v, lc);
  } else if (cmd == "set-parity") {
    Parity p;
    if (!parseParity(v, &p)) bad("parity: '" + v + "' is not none, even or odd");
    c.new_value = p == Parity::kEven ? 1 : p == Parity::kOdd ? 2 : 0;
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
void parseLimits(const Words& w, CommissionCommand& c) {
  if (w.has("type") && w.get("type") != "yespeed_pdu")
    bad("--type: " + c.command + " is a yespeed_pdu command; '" + w.get("type") +
        "' has no limits");
  c.type = "yespeed_pdu";
  if (!w.has("address")) bad("--address: missing (1-247)");
  c.address = intIn("--address", w.get("address"), 1, 247);
  w.atMost(1);
  if (c.command == "get-limits") return;
  static const char* kOptions[3] = {"over-voltage", "under-voltage", "over-current"};
  bool all = true;
  for (size_t i = 0; i < 3; ++i) {
    const std::string option = kOptions[i];
    if (!w.has(option)) {
      all = false;
      continue;
    }
    const std::string text = w.get(option);
    std::istringstream in(text);
    double v = 0;
    char rest = 0;
    if (!(in >> v) || in >> rest)
      bad("--" + option + ": '" + text + "' is not a number (" + YespeedPdu::kLimitUnits[i] + ")");
    uint16_t reg = 0;
    const std::string problem = YespeedPdu::limitToRegister(i, v, &reg, "--" + option);
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
void parseAnyAddress(const Words& w, CommissionCommand& c) {
  if (!w.has("address")) bad("--address: missing (1-255)");
  c.address = intIn("--address", w.get("address"), 1, 255);
}

void parseTable(const Words& w, CommissionCommand& c) {
  parseAnyAddress(w, c);
  c.table = w.word(1, "table", "coils, discrete-inputs, holding or input-registers");
  const bool bits = c.table == "coils" || c.table == "discrete-inputs";
  if (!bits && c.table != "holding" && c.table != "input-registers")
    bad("table: '" + c.table + "' is not coils, discrete-inputs, holding or input-registers");
  c.start = intIn("start", w.word(2, "start", "0-65535"), 0, 65535);
  if (c.command == "write") {
    if (c.table != "coils" && c.table != "holding")
      bad("table: " + c.table + " cannot be written (coils or holding)");
    const size_t n = w.positional().size();
    if (n < 4) bad("value: missing (" + std::string(bits ? "0 or 1" : "0-65535") + ")");
    const size_t max = bits ? kMaxWriteBits : kMaxWriteRegisters;
    if (n - 3 > max)
      bad("value: " + std::to_string(n - 3) + " values, at most " + std::to_string(max));
    for (size_t i = 3; i < n; ++i)
      c.values.push_back(
          static_cast<uint16_t>(intIn("value", w.positional()[i], 0, bits ? 1 : 65535)));
    c.count = static_cast<int>(c.values.size());
    c.multiple = w.has("multiple");
  } else {
    w.atMost(4);
    const int max = bits ? kMaxReadBits : kMaxReadRegisters;
    if (w.positional().size() > 3) c.count = intIn("count", w.positional()[3], 1, max);
  }
  if (c.start + c.count > 65536)
    bad("start: " + std::to_string(c.start) + " + " + std::to_string(c.count) + " passes 65535");
  if (c.command == "watch") {
    if (w.has("interval")) c.interval = secondsIn("--interval", w.get("interval"), 0.01, 3600);
    if (w.has("count")) c.polls = intIn("--count", w.get("count"), 1, 100000000);
  }
}

}  // namespace

bool parseCommission(const std::vector<std::string>& args, CommissionCommand* out,
                     std::string* error) {
  try {
    const Words w(args);
    CommissionCommand c;
    c.json = w.has("json");
    c.yes = w.has("yes");
    c.command = w.word(0, "command", "see --help");
    const auto known = commandOptions().find(c.command);
    if (known == commandOptions().end())
      bad("command: '" + c.command + "' is not known (see --help)");
    w.allowOnly(c.command, known->second);
    parseLink(w, c);
    if (c.command == "scan") {
      parseScan(w, c);
    } else if (c.command == "read" || c.command == "write" || c.command == "watch") {
      parseTable(w, c);
    } else if (c.command == "get-limits" || c.command == "set-limits") {
      parseLimits(w, c);
    } else if (c.command == "info") {
      parseAnyAddress(w, c);
      w.atMost(1);
    } else {
      parseDevice(w, c);
    }
    *out = c;
    return true;
  } catch (const BadArgument& e) {
    *error = e.message;
    return false;
  }
}

}  // namespace modbus_rtu_driver
