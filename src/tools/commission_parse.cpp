#include "modbus_rtu_driver/tools/commission_parse.h"

#include <algorithm>

#include "modbus_rtu_driver/core/modbus/switch_words.h"
#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/tools/commission_session.h"
#include "modbus_rtu_driver/tools/commission_values.h"

namespace modbus_rtu_driver::commission_args {

namespace {

// The value of a word its validator (commission_validators.cpp) has already checked, parsed by
// `parse` (parseParity, parseTableName). Should the two ever disagree: the parser's message.
template <typename T>
T parseChecked(std::optional<T> (*parse)(std::string_view, std::string*), std::string_view text,
               const std::string& what) {
  std::string why;
  const std::optional<T> value = parse(text, &why);
  if (!value) bad(what + ": " + why);
  return *value;
}

}  // namespace

void parseLink(const Parsed& p, CommissionCommand& c) {
  if (!p.top.count("--port")) bad("--port: missing (the serial device, e.g. /dev/ttyUSB0)");
  c.link.port = p.w.port;
  std::string port_error;
  if (!parseLinkTarget(c.link.port, &c.target, &port_error)) bad("--" + port_error);
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
  if (c.command == "scan" && c.target.type->answers_for_silence)
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
  // Each item was checked by baudList / parityList.
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
      c.parities.push_back(parseChecked(parseParity, name, "--parities"));
  if (c.addresses.empty() || c.bauds.empty() || c.parities.empty())
    bad("--addresses / --bauds / --parities: empty list");
  c.first_only = p.has("--first");
}
namespace {

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
}  // namespace

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
      c.new_value = static_cast<int>(parseChecked(parseParity, v, "value"));
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
  c.table = parseChecked(parseTableName, w.table, "table");  // checked by tableName
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

}  // namespace modbus_rtu_driver::commission_args
