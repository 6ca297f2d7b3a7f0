#include "modbus_rtu_driver/core/bus_config.h"

#include <yaml-cpp/yaml.h>

#include <cctype>
#include <map>
#include <set>
#include <sstream>

#include "modbus_rtu_driver/devices/registry.h"

namespace modbus_rtu_driver {

namespace {

const std::set<std::string> kDeviceKeys = {
    "type",       "address",    "poll_rate", "outputs",         "inputs",   "reply_delay",
    "safe_state", "on_restart", "on_start",  "command_timeout", "heartbeat"};
// The master role's keys beside the link's.
const std::set<std::string> kBusKeys = {
    "role",       "diagnostic_period", "devices",         "allow_raw_writes", "publish_on_change",
    "keep_alive", "heartbeat",         "shutdown_timeout"};
const std::set<std::string> kSlaveKeys = {"slave_id",          "coils",           "discrete_inputs",
                                          "holding_registers", "input_registers", "names"};
const std::set<std::string> kLinkKeys = {
    "port",         "baud",    "parity",  "data_bits", "stop_bits",   "response_timeout",
    "byte_timeout", "retries", "min_gap", "direction", "low_latency", "late_reply_guard"};

struct ConfigError {
  std::string message;
};

[[noreturn]] void fail(const std::string& key, const std::string& what) {
  throw ConfigError{key + ": " + what};
}

std::string show(const YAML::Node& n) {
  if (n.IsScalar()) return "'" + n.Scalar() + "'";
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a map";
  return "nothing";
}

template <typename T>
T get(const YAML::Node& n, const std::string& key, const char* expected) {
  try {
    return n.as<T>();
  } catch (const YAML::Exception&) {
    fail(key, show(n) + " is not " + expected);
  }
}

double getNumber(const YAML::Node& n, const std::string& key) {
  return get<double>(n, key, "a number");
}

int getInt(const YAML::Node& n, const std::string& key) {
  const double v = getNumber(n, key);
  if (v != static_cast<int>(v)) fail(key, show(n) + " is not a whole number");
  return static_cast<int>(v);
}

void checkKeys(const YAML::Node& map, const std::string& where,
               const std::set<std::string>& known) {
  for (const auto& kv : map) {
    const std::string key = kv.first.as<std::string>();
    if (!known.count(key)) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      fail(where + key, "unknown key (known keys: " + list + ")");
    }
  }
}

std::vector<std::string> getNames(const YAML::Node& n, const std::string& key) {
  if (!n.IsSequence()) fail(key, show(n) + " is not a list of names");
  std::vector<std::string> names;
  for (const auto& item : n) names.push_back(get<std::string>(item, key, "a name"));
  return names;
}

// A value for every output channel: one scalar for all, or a map by channel name.
template <typename T, typename Parse>
std::vector<T> perChannel(const YAML::Node& n, const std::string& key,
                          const std::vector<std::string>& names, T none, Parse parse) {
  std::vector<T> values(names.size(), none);
  if (n.IsScalar()) {
    const T v = parse(n, key);
    for (T& x : values) x = v;
    return values;
  }
  if (!n.IsMap()) fail(key, show(n) + " is neither one value for all channels nor a map by name");
  for (const auto& kv : n) {
    const std::string channel = kv.first.as<std::string>();
    size_t i = 0;
    while (i < names.size() && names[i] != channel) ++i;
    if (i == names.size()) {
      std::string list;
      for (const auto& nm : names) list += (list.empty() ? "" : ", ") + nm;
      fail(key + "/" + channel, "no output channel of that name (outputs: " + list + ")");
    }
    values[i] = parse(kv.second, key + "/" + channel);
  }
  return values;
}

void parseHeartbeat(const YAML::Node& n, const std::string& key, std::string* topic,
                    double* timeout) {
  if (!n.IsMap()) fail(key, show(n) + " is not a map {topic: NAME, timeout: S}");
  checkKeys(n, key + "/", {"topic", "timeout"});
  if (!n["topic"]) fail(key + "/topic", "missing (the topic whose messages keep outputs armed)");
  *topic = get<std::string>(n["topic"], key + "/topic", "a topic name");
  if (topic->empty()) fail(key + "/topic", "empty");
  if (!n["timeout"]) fail(key + "/timeout", "missing (s without a message before the safe state)");
  *timeout = getNumber(n["timeout"], key + "/timeout");
  if (!(*timeout >= 0.05 && *timeout <= 3600))
    fail(key + "/timeout", std::to_string(*timeout) + " s is outside 0.05-3600 s");
}

void parseFailsafe(const YAML::Node& n, const std::string& where,
                   const std::vector<std::string>& names, FailsafeConfig* out) {
  if (n["safe_state"]) {
    out->safe_state = perChannel<SafeState>(
        n["safe_state"], where + "safe_state", names, SafeState::kHold,
        [](const YAML::Node& v, const std::string& key) {
          SafeState s;
          const std::string text = get<std::string>(v, key, "off, on or hold");
          if (!parseSafeState(text, &s)) fail(key, "'" + text + "' is not off, on or hold");
          return s;
        });
  }
  if (n["command_timeout"]) {
    out->command_timeout = perChannel<double>(
        n["command_timeout"], where + "command_timeout", names, 0.0,
        [](const YAML::Node& v, const std::string& key) {
          const double s = getNumber(v, key);
          if (!(s == 0 || (s >= 0.05 && s <= 3600)))
            fail(key, std::to_string(s) + " s is outside 0.05-3600 s (0 = none)");
          return s;
        });
    for (size_t i = 0; i < names.size(); ++i) {
      if (out->command_timeout[i] > 0 && out->safeStateOf(i) == SafeState::kHold)
        fail(where + "command_timeout/" + names[i],
             "needs a safe_state of off or on for that channel (it is hold)");
    }
  }
  if (n["on_restart"]) {
    const std::string text =
        get<std::string>(n["on_restart"], where + "on_restart", "restore, safe or leave");
    if (!parseOnRestart(text, &out->on_restart))
      fail(where + "on_restart", "'" + text + "' is not restore, safe or leave");
  }
  if (n["on_start"]) {
    const std::string text = get<std::string>(n["on_start"], where + "on_start", "safe or keep");
    if (text != "safe" && text != "keep")
      fail(where + "on_start", "'" + text + "' is not safe or keep");
    out->on_start_safe = text == "safe";
  }
  if (n["heartbeat"])
    parseHeartbeat(n["heartbeat"], where + "heartbeat", &out->heartbeat_topic,
                   &out->heartbeat_timeout);
}

DeviceConfig parseDevice(const std::string& name, const YAML::Node& n) {
  const std::string where = "devices/" + name + "/";
  if (!isValidRosName(name))
    fail("devices/" + name,
         "device name is not a valid ROS name (a letter, then letters, digits or '_')");
  if (!n.IsMap()) fail("devices/" + name, show(n) + " is not a map of device settings");
  checkKeys(n, where, kDeviceKeys);
  DeviceConfig d;
  d.name = name;
  if (!n["type"]) {
    fail(
        where + "type", "missing (one of " + [] {
          std::string s;
          for (const auto& t : knownDeviceTypes()) s += (s.empty() ? "" : ", ") + t;
          return s;
        }() + ")");
  }
  d.type = get<std::string>(n["type"], where + "type", "a device type");
  if (!n["address"]) fail(where + "address", "missing (the device's slave address, 1-255)");
  d.address = getInt(n["address"], where + "address");
  if (n["poll_rate"]) d.poll_rate = getNumber(n["poll_rate"], where + "poll_rate");
  if (n["reply_delay"]) d.reply_delay = getNumber(n["reply_delay"], where + "reply_delay");
  if (n["outputs"]) d.outputs = getNames(n["outputs"], where + "outputs");
  if (n["inputs"]) d.inputs = getNames(n["inputs"], where + "inputs");
  const std::string problem = validateDeviceConfig(d);
  if (!problem.empty()) throw ConfigError{problem};
  parseFailsafe(n, where, outputNamesOf(d), &d.failsafe);
  return d;
}

void parseLink(const YAML::Node& root, LinkConfig* out) {
  LinkConfig& link = *out;
  if (root["port"]) link.port = get<std::string>(root["port"], "port", "a device path");
  if (root["baud"]) link.baud = getInt(root["baud"], "baud");
  if (root["parity"]) {
    const std::string p = get<std::string>(root["parity"], "parity", "none, even or odd");
    if (!parseParity(p, &link.parity)) fail("parity", "'" + p + "' is not none, even or odd");
  }
  if (root["data_bits"]) link.data_bits = getInt(root["data_bits"], "data_bits");
  if (root["stop_bits"]) link.stop_bits = getInt(root["stop_bits"], "stop_bits");
  if (root["response_timeout"])
    link.response_timeout = getNumber(root["response_timeout"], "response_timeout");
  if (root["byte_timeout"]) link.byte_timeout = getNumber(root["byte_timeout"], "byte_timeout");
  if (root["retries"]) link.retries = getInt(root["retries"], "retries");
  if (root["late_reply_guard"])
    link.late_reply_guard = getNumber(root["late_reply_guard"], "late_reply_guard");
  if (root["min_gap"]) link.min_gap = getNumber(root["min_gap"], "min_gap");
  if (root["low_latency"])
    link.low_latency = get<bool>(root["low_latency"], "low_latency", "true or false");
  if (root["direction"]) {
    const std::string d =
        get<std::string>(root["direction"], "direction", "auto, rts_high, rts_low");
    if (d == "auto")
      link.direction = DirectionControl::kAuto;
    else if (d == "rts_high")
      link.direction = DirectionControl::kRtsHigh;
    else if (d == "rts_low")
      link.direction = DirectionControl::kRtsLow;
    else
      fail("direction", "'" + d + "' is not auto, rts_high or rts_low");
  }
  const std::string link_problem = validateLinkConfig(link);
  if (!link_problem.empty()) throw ConfigError{link_problem};
}

double parseDiagnosticPeriod(const YAML::Node& root) {
  if (!root["diagnostic_period"]) return 1.0;
  const double p = getNumber(root["diagnostic_period"], "diagnostic_period");
  if (!(p >= 0.1 && p <= 60))
    fail("diagnostic_period", std::to_string(p) + " s is outside 0.1-60 s");
  return p;
}

std::set<std::string> with(std::set<std::string> keys, const std::set<std::string>& more) {
  keys.insert(more.begin(), more.end());
  return keys;
}

void parse(const YAML::Node& root, BusConfig* out) {
  if (!root.IsMap()) fail("(root)", "the configuration is not a map of settings");
  checkKeys(root, "", with(kLinkKeys, kBusKeys));
  parseLink(root, &out->link);
  if (root["allow_raw_writes"])
    out->allow_raw_writes =
        get<bool>(root["allow_raw_writes"], "allow_raw_writes", "true or false");
  if (root["role"]) {
    out->role = get<std::string>(root["role"], "role", "master or slave");
    if (out->role != "master") fail("role", "'" + out->role + "' is not master");
  }
  out->diagnostic_period = parseDiagnosticPeriod(root);
  if (root["publish_on_change"])
    out->publish_on_change =
        get<bool>(root["publish_on_change"], "publish_on_change", "true or false");
  if (root["keep_alive"]) {
    out->keep_alive = getNumber(root["keep_alive"], "keep_alive");
    if (!(out->keep_alive >= 0.1 && out->keep_alive <= 3600))
      fail("keep_alive", std::to_string(out->keep_alive) + " s is outside 0.1-3600 s");
  }
  if (root["heartbeat"])
    parseHeartbeat(root["heartbeat"], "heartbeat", &out->heartbeat_topic, &out->heartbeat_timeout);
  if (root["shutdown_timeout"]) {
    out->shutdown_timeout = getNumber(root["shutdown_timeout"], "shutdown_timeout");
    if (!(out->shutdown_timeout >= 0 && out->shutdown_timeout <= 60))
      fail("shutdown_timeout", std::to_string(out->shutdown_timeout) + " s is outside 0-60 s");
  }
  const YAML::Node devices = root["devices"];
  if (!devices) fail("devices", "missing (a map of device name -> settings)");
  if (!devices.IsMap() || devices.size() == 0)
    fail("devices", show(devices) + " is not a non-empty map of device name -> settings");
  std::map<int, std::string> by_address;
  for (const auto& kv : devices) {
    const std::string name = kv.first.as<std::string>();
    DeviceConfig d = parseDevice(name, kv.second);
    auto [it, fresh] = by_address.emplace(d.address, name);
    if (!fresh)
      fail("devices/" + name + "/address",
           std::to_string(d.address) + " is already used by device '" + it->second + "'");
    out->devices.push_back(std::move(d));
  }
}

uint16_t getTableSize(const YAML::Node& root, const char* key, uint16_t fallback) {
  if (!root[key]) return fallback;
  const int n = getInt(root[key], key);
  if (n < 0 || n > 10000) fail(key, std::to_string(n) + " is outside 0-10000");
  return static_cast<uint16_t>(n);
}

void parseNames(const YAML::Node& n, const std::string& key, uint16_t size,
                std::map<uint16_t, std::string>* out) {
  if (!n) return;
  if (!n.IsMap()) fail(key, show(n) + " is not a map of address -> name");
  std::set<std::string> seen;
  for (const auto& kv : n) {
    // address: name as in the DM500 docs; ROS parameter keys are strings, so a launch file
    // writes "6": name (quoted) or name: 6, and all three forms are accepted.
    const std::string k = kv.first.as<std::string>();
    const bool address_first = !k.empty() && std::isdigit(static_cast<unsigned char>(k[0]));
    const int address = getInt(address_first ? kv.first : kv.second, key);
    const std::string name = address_first ? get<std::string>(kv.second, key, "a name") : k;
    const std::string where = key + "/" + std::to_string(address);
    if (address < 0 || address >= size)
      fail(where, "address is outside the table (0-" + std::to_string(size - 1) + ")");
    if (!isValidRosName(name))
      fail(where, "'" + name + "' is not a valid ROS name (a letter, then letters, digits or '_')");
    if (!seen.insert(name).second) fail(where, "'" + name + "' is given twice");
    (*out)[static_cast<uint16_t>(address)] = name;
  }
}

void parseSlave(const YAML::Node& root, SlaveConfig* out) {
  if (!root.IsMap()) fail("(root)", "the configuration is not a map of settings");
  checkKeys(root, "", with(with(kLinkKeys, {"role", "diagnostic_period"}), kSlaveKeys));
  parseLink(root, &out->link);
  const std::string role = root["role"] ? get<std::string>(root["role"], "role", "slave") : "";
  if (role != "slave") fail("role", "'" + role + "' is not slave");
  out->diagnostic_period = parseDiagnosticPeriod(root);
  if (!root["slave_id"]) fail("slave_id", "missing (the address this node answers, 1-247)");
  out->slave_id = getInt(root["slave_id"], "slave_id");
  if (out->slave_id < 1 || out->slave_id > 247)
    fail("slave_id", std::to_string(out->slave_id) + " is outside 1-247");
  out->coils = getTableSize(root, "coils", 64);
  out->discrete_inputs = getTableSize(root, "discrete_inputs", 64);
  out->holding_registers = getTableSize(root, "holding_registers", 64);
  out->input_registers = getTableSize(root, "input_registers", 64);
  const YAML::Node names = root["names"];
  if (names) {
    if (!names.IsMap()) fail("names", show(names) + " is not a map (coils, holding_registers)");
    checkKeys(names, "names/", {"coils", "holding_registers"});
    parseNames(names["coils"], "names/coils", out->coils, &out->coil_names);
    parseNames(names["holding_registers"], "names/holding_registers", out->holding_registers,
               &out->holding_names);
  }
}

// Runs a parser; its first error becomes the message.
template <typename Config>
bool parseWith(void (*parser)(const YAML::Node&, Config*), const YAML::Node& root, Config* out,
               std::string* error) {
  *out = Config{};
  try {
    parser(root, out);
    return true;
  } catch (const ConfigError& e) {
    if (error) *error = e.message;
  } catch (const YAML::Exception& e) {
    if (error) *error = std::string("configuration: ") + e.what();
  }
  return false;
}

}  // namespace

bool parseSlaveConfig(const YAML::Node& root, SlaveConfig* out, std::string* error) {
  return parseWith(parseSlave, root, out, error);
}

std::vector<std::string> configKeys() {
  std::vector<std::string> keys(kLinkKeys.begin(), kLinkKeys.end());
  keys.insert(keys.end(), kBusKeys.begin(), kBusKeys.end());
  for (const auto& k : kDeviceKeys) keys.push_back("devices/D/" + k);
  keys.insert(keys.end(), kSlaveKeys.begin(), kSlaveKeys.end());
  return keys;
}

bool isValidRosName(const std::string& name) {
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) return false;
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return true;
}

bool parseBusConfig(const YAML::Node& root, BusConfig* out, std::string* error) {
  return parseWith(parse, root, out, error);
}

}  // namespace modbus_rtu_driver
