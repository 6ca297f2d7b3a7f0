#include "modbus_rtu_driver/core/config/config_yaml.h"

#include <cctype>
#include <cmath>
#include <limits>

#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/core/modbus/text.h"

namespace modbus_rtu_driver {
namespace config {

const std::set<std::string> kLinkKeys = {"port",
                                         "baud",
                                         "parity",
                                         "data_bits",
                                         "stop_bits",
                                         "response_timeout",
                                         "byte_timeout",
                                         "retries",
                                         "min_gap",
                                         "direction",
                                         "low_latency",
                                         "late_reply_guard",
                                         "network_allowance"};

[[noreturn]] void fail(const std::string& key, const std::string& what) {
  throw ConfigError{key + ": " + what};
}

std::string show(const YAML::Node& n) {
  if (n.IsScalar()) return "'" + n.Scalar() + "'";
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a map";
  return "nothing";
}

Table getTable(const YAML::Node& n, const std::string& key) {
  const std::string text = get<std::string>(n, key, "a table name");
  std::string problem;
  const auto table = parseTableName(text, &problem);
  if (!table) fail(key, problem);
  return *table;
}

bool getSwitch(const YAML::Node& n, const std::string& key) {
  const std::string words = std::string(kSwitchWords);
  const auto on = parseSwitch(get<std::string>(n, key, ("one of " + words).c_str()));
  if (!on) fail(key, show(n) + " is not one of " + words);
  return *on;
}

double getNumber(const YAML::Node& n, const std::string& key) {
  return get<double>(n, key, "a number");
}

int getInt(const YAML::Node& n, const std::string& key) {
  int hex = 0;  // register addresses are often written 0x0156, as YAML (and rosparam) allow
  if (n.IsScalar() && n.Scalar().rfind("0x", 0) == 0 && YAML::convert<int>::decode(n, hex))
    return hex;
  const double v = getNumber(n, key);
  // Range first: casting a double outside int's range is undefined behaviour.
  if (!(std::fabs(v) <= std::numeric_limits<int>::max())) fail(key, show(n) + " is too large");
  if (v != std::floor(v)) fail(key, show(n) + " is not a whole number");
  return static_cast<int>(v);
}

void checkKeys(const YAML::Node& map, const std::string& where,
               const std::set<std::string>& known) {
  for (const auto& kv : map) {
    const std::string key = kv.first.as<std::string>();
    if (!known.count(key)) fail(where + key, "unknown key (known keys: " + join(known) + ")");
  }
}

std::set<std::string> with(std::set<std::string> keys, const std::set<std::string>& more) {
  keys.insert(more.begin(), more.end());
  return keys;
}

void parseLink(const YAML::Node& root, LinkConfig* out) {
  readLink(root, out);
  const std::string link_problem = validateLinkConfig(*out);
  if (!link_problem.empty()) throw ConfigError{link_problem};
}

void readLink(const YAML::Node& root, LinkConfig* out) {
  LinkConfig& link = *out;
  if (root["port"]) link.port = get<std::string>(root["port"], "port", "a device path");
  if (root["baud"]) link.baud = getInt(root["baud"], "baud");
  if (root["parity"]) {
    const std::string p = get<std::string>(root["parity"], "parity", "none, even or odd");
    std::string problem;
    const auto parity = parseParity(p, &problem);
    if (!parity) fail("parity", problem);
    link.parity = *parity;
  }
  if (root["data_bits"]) link.data_bits = getInt(root["data_bits"], "data_bits");
  if (root["stop_bits"]) link.stop_bits = getInt(root["stop_bits"], "stop_bits");
  if (root["response_timeout"])
    link.response_timeout = getNumber(root["response_timeout"], "response_timeout");
  if (root["byte_timeout"]) link.byte_timeout = getNumber(root["byte_timeout"], "byte_timeout");
  if (root["retries"]) link.retries = getInt(root["retries"], "retries");
  if (root["late_reply_guard"])
    link.late_reply_guard = getNumber(root["late_reply_guard"], "late_reply_guard");
  if (root["network_allowance"])
    link.network_allowance = getNumber(root["network_allowance"], "network_allowance");
  if (root["min_gap"]) link.min_gap = getNumber(root["min_gap"], "min_gap");
  if (root["low_latency"]) link.low_latency = getSwitch(root["low_latency"], "low_latency");
  if (root["direction"])
    link.direction = getNamed(root["direction"], "direction", kDirectionControlNames);
}

double parseDiagnosticPeriod(const YAML::Node& root) {
  if (!root["diagnostic_period"]) return 1.0;
  const double p = getNumber(root["diagnostic_period"], "diagnostic_period");
  if (!(p >= 0.1 && p <= 60)) fail("diagnostic_period", numberText(p) + " s is outside 0.1-60 s");
  return p;
}

}  // namespace config

bool isValidRosName(const std::string& name) {
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) return false;
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return true;
}

}  // namespace modbus_rtu_driver
