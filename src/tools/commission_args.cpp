// Command line of modbus_rtu_commission: every value is checked against the manuals' ranges
// before anything is opened or sent.
#include <algorithm>
#include <map>
#include <sstream>

#include "modbus_rtu_driver/tools/commission.h"

namespace modbus_rtu_driver {

namespace {

const int kLdBauds[] = {1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200};

bool toInt(const std::string& s, int* out) {
  try {
    size_t used = 0;
    const long v = std::stol(s, &used, 0);
    if (used != s.size()) return false;
    *out = static_cast<int>(v);
    return true;
  } catch (...) {
    return false;
  }
}

struct Problem {
  std::string message;
};

int intOption(const std::map<std::string, std::string>& o, const std::string& key, int fallback,
              int lo, int hi) {
  auto it = o.find(key);
  if (it == o.end()) return fallback;
  int v = 0;
  if (!toInt(it->second, &v) || v < lo || v > hi)
    throw Problem{"--" + key + ": '" + it->second + "' is outside " + std::to_string(lo) + "-" +
                  std::to_string(hi)};
  return v;
}

int positionalInt(const std::vector<std::string>& p, size_t i, const std::string& what, int lo,
                  int hi) {
  if (i >= p.size())
    throw Problem{what + ": missing (" + std::to_string(lo) + "-" + std::to_string(hi) + ")"};
  int v = 0;
  if (!toInt(p[i], &v) || v < lo || v > hi)
    throw Problem{what + ": '" + p[i] + "' is outside " + std::to_string(lo) + "-" +
                  std::to_string(hi)};
  return v;
}

}  // namespace

std::string commissionUsage() {
  return R"(usage: modbus_rtu_commission --port PORT [--baud B] [--parity none|even|odd]
         [--timeout S] [--json] [--yes] COMMAND ...
commands:
  scan [--from A] [--to B] [--bauds 9600,19200|all] [--parities none,even,odd|all] [--first]
  info --address A
  get-address --type ld58a08|lc_relay8 [--address A]  (without --address: the board must be
                                                         alone on the bus; LD via 0xFF, LC via 0)
  set-address --type ld58a08|lc_relay8 [--address A] NEW
  get-baud --type T --address A          set-baud --type T --address A BAUD
  get-parity --address A                 set-parity --address A none|even|odd   (ld58a08)
  set-return-delay --address A MS        (ld58a08, 0-1000 ms in steps of 40)
  set-save --address A on|off            (ld58a08 power-down save of PWM settings)
  factory-reset [--address A]            (ld58a08; without --address through 0xFF)
  read --address A coils|discrete-inputs|holding|input-registers START [COUNT]
  write --address A coils|holding START VALUE...
  watch --address A TABLE START [COUNT] [--interval S] [--count N]
Changes to how a device answers (address, baud, parity, return delay, factory reset) ask for
confirmation unless --yes. Baud and parity take effect after the device is powered off and on.
exit codes: 0 ok, 2 bad arguments, 3 not found / no answer, 4 refused by the device (Modbus
exception), 5 other bus error (CRC, I/O, port), 6 not confirmed
)";
}

bool parseCommission(const std::vector<std::string>& args, CommissionCommand* out,
                     std::string* error) {
  static const std::vector<std::string> kFlags = {"json", "yes", "first"};
  std::map<std::string, std::string> o;
  std::vector<std::string> p;
  try {
    for (size_t i = 0; i < args.size(); ++i) {
      const std::string& a = args[i];
      if (a.rfind("--", 0) != 0) {
        p.push_back(a);
        continue;
      }
      const std::string key = a.substr(2);
      if (std::find(kFlags.begin(), kFlags.end(), key) != kFlags.end()) {
        o[key] = "1";
      } else if (i + 1 < args.size()) {
        o[key] = args[++i];
      } else {
        throw Problem{a + ": missing value"};
      }
    }
    static const std::vector<std::string> kKnown = {
        "port", "baud",  "parity",   "timeout", "json",    "yes",      "first", "from",
        "to",   "bauds", "parities", "type",    "address", "interval", "count"};
    for (const auto& kv : o)
      if (std::find(kKnown.begin(), kKnown.end(), kv.first) == kKnown.end())
        throw Problem{"--" + kv.first + ": unknown option"};
    CommissionCommand c;
    if (!o.count("port")) throw Problem{"--port: missing (the serial device, e.g. /dev/ttyUSB0)"};
    c.link.port = o["port"];
    c.link.baud = intOption(o, "baud", 9600, 1200, 115200);
    if (!isStandardBaud(c.link.baud))
      throw Problem{"--baud: " + o["baud"] + " is not a standard rate"};
    if (o.count("parity") && !parseParity(o["parity"], &c.link.parity))
      throw Problem{"--parity: '" + o["parity"] + "' is not none, even or odd"};
    c.link.retries = 0;
    c.link.response_timeout = 0.05 + 30.0 * 11 / c.link.baud;  // short: scans try many addresses
    if (o.count("timeout")) {
      std::istringstream t(o["timeout"]);
      if (!(t >> c.link.response_timeout) || c.link.response_timeout < 0.005 ||
          c.link.response_timeout > 10)
        throw Problem{"--timeout: '" + o["timeout"] + "' is outside 0.005-10 s"};
    }
    c.json = o.count("json");
    c.yes = o.count("yes");
    if (p.empty()) throw Problem{"command: missing (see --help)"};
    c.command = p[0];
    if (o.count("type")) {
      c.type = o["type"];
      if (c.type != "ld58a08" && c.type != "lc_relay8")
        throw Problem{"--type: '" + c.type + "' is not ld58a08 or lc_relay8"};
    }
    const bool lc = c.type == "lc_relay8";
    c.address = intOption(o, "address", -1, 1, 255);
    auto needType = [&] {
      if (c.type.empty()) throw Problem{"--type: missing (ld58a08 or lc_relay8)"};
    };
    auto needAddress = [&](int hi) {
      if (c.address < 0) throw Problem{"--address: missing (1-" + std::to_string(hi) + ")"};
      if (c.address > hi)
        throw Problem{"--address: " + std::to_string(c.address) + " is outside 1-" +
                      std::to_string(hi)};
    };
    const std::string& cmd = c.command;
    if (cmd == "scan") {
      c.from = intOption(o, "from", 1, 1, 255);
      c.to = intOption(o, "to", 247, 1, 255);
      if (c.to < c.from) throw Problem{"--to: " + std::to_string(c.to) + " is below --from"};
      c.first_only = o.count("first");
      const std::string bauds = o.count("bauds") ? o["bauds"] : std::to_string(c.link.baud);
      if (bauds == "all") {
        c.bauds.assign(std::begin(kLdBauds), std::end(kLdBauds));
      } else {
        std::istringstream in(bauds);
        for (std::string b; std::getline(in, b, ',');) {
          int v = 0;
          if (!toInt(b, &v) || !isStandardBaud(v))
            throw Problem{"--bauds: '" + b + "' is not one of 1200 ... 115200"};
          c.bauds.push_back(v);
        }
      }
      const std::string parities = o.count("parities") ? o["parities"] : parityName(c.link.parity);
      std::istringstream in(parities == "all" ? "none,even,odd" : parities);
      for (std::string s; std::getline(in, s, ',');) {
        Parity par;
        if (!parseParity(s, &par))
          throw Problem{"--parities: '" + s + "' is not none, even or odd"};
        c.parities.push_back(par);
      }
    } else if (cmd == "get-address") {
      needType();
      if (c.address >= 0) needAddress(lc ? 255 : 247);
    } else if (cmd == "set-address") {
      needType();
      if (c.address >= 0) needAddress(lc ? 255 : 247);
      c.new_value = positionalInt(p, 1, "new address", 1, lc ? 255 : 247);
    } else if (cmd == "get-baud" || cmd == "set-baud") {
      needType();
      needAddress(lc ? 255 : 247);
      if (cmd == "set-baud") {
        const int baud = positionalInt(p, 1, "baud", 1200, 115200);
        const int* codes = std::find(std::begin(kLdBauds), std::end(kLdBauds), baud);
        const int code = static_cast<int>(codes - std::begin(kLdBauds));
        if (lc ? (code < 2 || code > 4) : codes == std::end(kLdBauds))
          throw Problem{
              "baud: " + std::to_string(baud) + " is not one of " +
              (lc ? "4800, 9600, 19200" : "1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200")};
        c.new_value = code;  // the LC board uses the same codes 2-4
      }
    } else if (cmd == "get-parity" || cmd == "set-parity") {
      needAddress(247);
      if (cmd == "set-parity") {
        Parity par;
        if (p.size() < 2 || !parseParity(p[1], &par))
          throw Problem{"parity: '" + (p.size() < 2 ? std::string() : p[1]) +
                        "' is not none, even or odd"};
        c.new_value = par == Parity::kEven ? 1 : par == Parity::kOdd ? 2 : 0;
      }
    } else if (cmd == "set-return-delay") {
      needAddress(247);
      const int ms = positionalInt(p, 1, "delay", 0, 1000);
      if (ms % 40) throw Problem{"delay: " + std::to_string(ms) + " ms is not a multiple of 40 ms"};
      c.new_value = ms / 40;
    } else if (cmd == "set-save") {
      needAddress(247);
      if (p.size() < 2 || (p[1] != "on" && p[1] != "off"))
        throw Problem{"save: '" + (p.size() < 2 ? std::string() : p[1]) + "' is not on or off"};
      c.new_value = p[1] == "on";
    } else if (cmd == "factory-reset") {
      if (c.address >= 0) needAddress(247);
    } else if (cmd == "info") {
      needAddress(255);
    } else if (cmd == "read" || cmd == "write" || cmd == "watch") {
      needAddress(255);
      if (p.size() < 2)
        throw Problem{"table: missing (coils, discrete-inputs, holding, input-registers)"};
      c.table = p[1];
      const bool bits = c.table == "coils" || c.table == "discrete-inputs";
      if (!bits && c.table != "holding" && c.table != "input-registers")
        throw Problem{"table: '" + c.table +
                      "' is not coils, discrete-inputs, holding or input-registers"};
      c.start = positionalInt(p, 2, "start", 0, 65535);
      if (cmd == "write") {
        if (c.table != "coils" && c.table != "holding")
          throw Problem{"table: '" + c.table + "' cannot be written (coils or holding)"};
        if (p.size() < 4) throw Problem{"values: missing"};
        for (size_t i = 3; i < p.size(); ++i)
          c.values.push_back(
              static_cast<uint16_t>(positionalInt(p, i, "value", 0, bits ? 1 : 65535)));
        c.count = static_cast<int>(c.values.size());
        if (c.count > (bits ? 1968 : 123)) throw Problem{"values: too many for one request"};
      } else {
        c.count = p.size() > 3 ? positionalInt(p, 3, "count", 1, bits ? 2000 : 125) : 1;
      }
      if (c.start + c.count > 65536) throw Problem{"start: range passes 65535"};
      if (cmd == "watch") {
        c.polls = intOption(o, "count", 0, 0, 1000000);
        if (o.count("interval")) {
          std::istringstream t(o["interval"]);
          if (!(t >> c.interval) || c.interval < 0.01 || c.interval > 3600)
            throw Problem{"--interval: '" + o["interval"] + "' is outside 0.01-3600 s"};
        }
      }
    } else {
      throw Problem{"command: '" + cmd + "' is not known (see --help)"};
    }
    *out = c;
    return true;
  } catch (const Problem& e) {
    *error = e.message;
    return false;
  }
}

}  // namespace modbus_rtu_driver
