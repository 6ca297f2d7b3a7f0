// The YAML of a generic device's signals: `signals:` in the device, or `template: FILE` with a
// `signals:` list of its own. Every key is checked; errors name it (config_yaml.h's rules).
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "modbus_rtu_driver/core/config/config_yaml.h"
#include "modbus_rtu_driver/core/config/device_types.h"
#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/core/config/signal.h"

namespace modbus_rtu_driver {

using namespace config;

const std::vector<std::string> kSignalMapKeys = {"signals", "template", "max_gap"};
const std::vector<std::string> kSignalKeys = {
    "name", "table",    "address", "type", "word_order", "scale",          "offset",
    "unit", "writable", "min",     "max",  "poll_rate",  "write_function", "safe_value"};

namespace {

// Names a device already uses for its own topics.
const std::set<std::string> kReservedNames = {"signals", "outputs", "set_outputs", "failsafe"};

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

double finite(const YAML::Node& n, const std::string& key) {
  const double v = getNumber(n, key);
  if (!std::isfinite(v)) fail(key, show(n) + " is not a finite number");
  return v;
}

// safe_value: a bit takes the switch words (on/off, true/false, yes/no, 1/0); a number is checked
// as a write of it would be (min / max, after rounding to the register's steps, and the type's
// range).
void parseSafeValue(const YAML::Node& n, const std::string& key, SignalConfig* s) {
  if (!s->writable) fail(key, "only for writable signals (writable: true)");
  double v = 0;
  if (s->type == SignalType::kBool) {
    const auto on = n.IsScalar() ? parseSwitch(n.Scalar()) : std::nullopt;
    if (!on)
      fail(key,
           show(n) + " is not one of " + std::string(kSwitchWords) + " for the bit " + s->name);
    v = *on ? 1.0 : 0.0;
  } else {
    v = finite(n, key);
  }
  std::vector<uint16_t> words;
  const std::string problem = writeValueProblem(*s, v, &words);
  if (!problem.empty()) fail(key, problem);
  s->safe_value = v;
}

SignalConfig parseSignal(const YAML::Node& n, const std::string& where) {
  if (!n.IsMap()) fail(where, show(n) + " is not a map {name, table, address, type, ...}");
  checkKeys(n, where + "/", std::set<std::string>(kSignalKeys.begin(), kSignalKeys.end()));
  SignalConfig s;
  for (const char* required : {"name", "table", "address"})
    if (!n[required]) fail(where + "/" + required, "missing");
  s.name = get<std::string>(n["name"], where + "/name", "a name");
  if (!isValidRosName(s.name))
    fail(where + "/name", "'" + s.name +
                              "' is not a valid ROS name (a letter, then letters, "
                              "digits or '_')");
  if (kReservedNames.count(s.name))
    fail(where + "/name", "'" + s.name + "' is taken by the device's own topics");
  const std::string at = where + "/";  // keys below: signals[i]/key
  s.table = getTable(n["table"], at + "table");
  const int address = getInt(n["address"], at + "address");
  if (address < 0 || address > 0xFFFF)
    fail(at + "address", std::to_string(address) + " is outside 0-65535");
  s.address = static_cast<uint16_t>(address);
  const bool bits = isBitTable(s.table);
  s.type = bits ? SignalType::kBool : SignalType::kUint16;
  if (n["type"]) s.type = getNamed(n["type"], at + "type", kSignalTypeNames);
  if (bits != (s.type == SignalType::kBool))
    fail(at + "type", std::string(typeName(s.type)) + " does not fit a " + tableName(s.table) +
                          (bits ? " (bits are bool)" : " (bool is for coils and discrete inputs)"));
  if (address + s.words() - 1 > 0xFFFF)
    fail(at + "address", std::to_string(address) + " leaves no room for " +
                             std::to_string(s.words()) + " registers of " + typeName(s.type));
  if (n["word_order"]) {
    if (s.words() < 2) fail(at + "word_order", "only for 32- and 64-bit types");
    s.word_order = getNamed(n["word_order"], at + "word_order", kWordOrderNames);
  }
  for (const char* key : {"scale", "offset", "unit"})
    if (bits && n[key]) fail(at + key, std::string("not for bits (") + tableName(s.table) + ")");
  if (n["scale"]) {
    s.scale = finite(n["scale"], at + "scale");
    if (s.scale == 0.0) fail(at + "scale", "0 would make every value the same");
  }
  if (n["offset"]) s.offset = finite(n["offset"], at + "offset");
  if (n["unit"]) s.unit = get<std::string>(n["unit"], at + "unit", "a unit's name");
  if (n["writable"]) s.writable = getSwitch(n["writable"], at + "writable");
  if (s.writable && s.table != Table::kCoil && s.table != Table::kHoldingRegister)
    fail(at + "writable", std::string("a ") + tableName(s.table) + " cannot be written");
  for (const char* key : {"min", "max"}) {
    if (!n[key]) continue;
    if (!s.writable || bits) fail(at + key, "only for writable numbers");
    const double v = finite(n[key], at + key);
    const double raw = s.toRaw(v);
    if (raw < rawMin(s.type) || raw > rawMax(s.type))
      fail(at + key, number(v) + " is outside what " + typeName(s.type) + " holds (raw " +
                         number(rawMin(s.type)) + " to " + number(rawMax(s.type)) + ")");
    (std::string(key) == "min" ? s.min : s.max) = v;
  }
  if (s.min && s.max && *s.min > *s.max)
    fail(at + "min", number(*s.min) + " is above max " + number(*s.max));
  if (n["write_function"]) {
    if (!s.writable) fail(at + "write_function", "only for writable signals (writable: true)");
    s.write_function = getInt(n["write_function"], at + "write_function");
    if (s.write_function == 0)  // 0 stands for the default in SignalConfig, not in the YAML
      fail(at + "write_function",
           std::string("0 is not a write function (") + (bits ? "5 or 15)" : "6 or 16)"));
    const std::string problem = writeFunctionProblem(s);
    if (!problem.empty()) fail(at + "write_function", problem);
  }
  if (n["safe_value"]) parseSafeValue(n["safe_value"], at + "safe_value", &s);
  if (n["poll_rate"]) {
    const double r = getNumber(n["poll_rate"], at + "poll_rate");
    if (!validPollRate(r)) fail(at + "poll_rate", numberText(r) + kPollRateRange);
    s.poll_rate = r;
  }
  return s;
}

void parseSignalList(const YAML::Node& list, const std::string& key,
                     std::vector<SignalConfig>* out) {
  if (!list.IsSequence() || list.size() == 0)
    fail(key, show(list) + " is not a non-empty list of signals");
  for (size_t i = 0; i < list.size(); ++i)
    out->push_back(parseSignal(list[i], key + "[" + std::to_string(i) + "]"));
}

// Unique names, no two signals on the same register or bit.
void checkTogether(const std::vector<SignalConfig>& signals, const std::string& where) {
  std::set<std::string> names;
  for (size_t i = 0; i < signals.size(); ++i) {
    const SignalConfig& s = signals[i];
    if (!names.insert(s.name).second) fail(where + "signals", "'" + s.name + "' is given twice");
    for (size_t j = 0; j < i; ++j) {
      const SignalConfig& o = signals[j];
      if (o.table == s.table && s.address < o.address + o.words() &&
          o.address < s.address + s.words())
        fail(where + "signals", "'" + s.name + "' overlaps '" + o.name + "' (" +
                                    tableName(s.table) + " " + std::to_string(s.address) + ")");
    }
  }
}

std::string findPackage(const std::string& package, const std::string& key) {
  const char* path = std::getenv("ROS_PACKAGE_PATH");
  std::stringstream dirs(path ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    if (dir.empty()) continue;
    for (const std::string& candidate : {dir + "/" + package, dir}) {
      const bool named = candidate != dir || dir.substr(dir.find_last_of('/') + 1) == package;
      if (named && std::ifstream(candidate + "/package.xml")) return candidate;
    }
  }
  fail(key, "$(find " + package + "): no package of that name on ROS_PACKAGE_PATH");
}

}  // namespace

std::string resolveTemplatePath(const std::string& path, const std::string& key,
                                const std::string& base_dir) {
  if (path.empty()) fail(key, "empty");
  if (path.rfind("$(find ", 0) == 0) {
    const size_t close = path.find(')');
    if (close == std::string::npos) fail(key, "'" + path + "': $(find PKG) is not closed");
    return findPackage(path.substr(7, close - 7), key) + path.substr(close + 1);
  }
  if (path[0] == '/') return path;
  if (base_dir.empty())
    fail(key, "'" + path +
                  "' is relative, but the configuration's directory is not known "
                  "(set config_file, as bus.launch does, or use $(find PKG)/...)");
  return base_dir + "/" + path;
}

SignalMapConfig parseSignalMap(const YAML::Node& n, const std::string& where,
                               const std::string& base_dir) {
  SignalMapConfig out;
  if (n["template"]) {
    const std::string key = where + "template";
    const std::string file =
        resolveTemplatePath(get<std::string>(n["template"], key, "a file name"), key, base_dir);
    YAML::Node root;
    try {
      root = YAML::LoadFile(file);
    } catch (const YAML::Exception& e) {
      fail(key, "cannot load '" + file + "': " + e.what());
    }
    if (!root.IsMap()) fail(key, "'" + file + "' is not a map with a signals list");
    checkKeys(root, key + " " + file + ": ", {"signals", "description"});
    if (!root["signals"]) fail(key, "'" + file + "' has no signals list");
    parseSignalList(root["signals"], key + " " + file + ": signals", &out.signals);
  }
  if (n["signals"]) parseSignalList(n["signals"], where + "signals", &out.signals);
  if (out.signals.empty())
    fail(where + "signals", "missing (a list of signals, or template: FILE with one)");
  checkTogether(out.signals, where);
  if (n["max_gap"]) {
    out.max_gap = getInt(n["max_gap"], where + "max_gap");
    if (out.max_gap < 0 || out.max_gap > 123)
      fail(where + "max_gap", std::to_string(out.max_gap) + " is outside 0-123");
  }
  return out;
}

}  // namespace modbus_rtu_driver
