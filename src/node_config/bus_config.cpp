#include "modbus_rtu_driver/node_config/bus_config.h"

#include <algorithm>
#include <map>
#include <set>

#include "modbus_rtu_driver/core/config/config_yaml.h"
#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/core/config/slave_config.h"
#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/devices/registry.h"

namespace modbus_rtu_driver {

namespace {

using namespace config;

// The last three are the generic type's (core/config/signal.h: kSignalMapKeys).
const std::set<std::string> kDeviceKeys = {
    "type",        "address",    "poll_rate",  "outputs",  "inputs",
    "reply_delay", "safe_state", "on_restart", "on_start", "command_timeout",
    "heartbeat",   "signals",    "template",   "max_gap"};

// The master role's keys beside the link's.
const std::set<std::string> kBusKeys = {
    "role",       "diagnostic_period", "devices",          "allow_raw_writes",  "publish_on_change",
    "keep_alive", "heartbeat",         "shutdown_timeout", "realtime_priority", "lock_memory",
    "share",      "config_file",       "wire_log"};
const std::set<std::string> kShareKeys = {"listen",
                                          "read_only",
                                          "allow",
                                          "max_clients",
                                          "max_queue",
                                          "idle_timeout",
                                          "broadcast_turnaround",
                                          "answer_within"};

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
    if (i == names.size())
      fail(key + "/" + channel, "no output channel of that name (outputs: " + join(names) + ")");
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
    fail(key + "/timeout", numberText(*timeout) + " s is outside 0.05-3600 s");
}

void parseFailsafe(const YAML::Node& n, const std::string& where,
                   const std::vector<std::string>& names, FailsafeConfig* out,
                   std::vector<std::string>* deprecated) {
  if (n["safe_state"]) {
    out->safe_state = perChannel<SafeState>(
        n["safe_state"], where + "safe_state", names, SafeState::kLeave,
        [](const YAML::Node& v, const std::string& key) {
          SafeState s;
          const std::string text = get<std::string>(v, key, safeStateWords().c_str());
          if (!parseSafeState(text, &s))
            fail(key, "'" + text + "' is not one of " + safeStateWords());
          return s;
        });
  }
  if (n["command_timeout"]) {
    out->command_timeout =
        perChannel<double>(n["command_timeout"], where + "command_timeout", names, 0.0,
                           [](const YAML::Node& v, const std::string& key) {
                             const double s = getNumber(v, key);
                             if (!(s == 0 || (s >= 0.05 && s <= 3600)))
                               fail(key, numberText(s) + " s is outside 0.05-3600 s (0 = none)");
                             return s;
                           });
    for (size_t i = 0; i < names.size(); ++i) {
      if (out->command_timeout[i] > 0 && out->safeStateOf(i) == SafeState::kLeave)
        fail(where + "command_timeout/" + names[i],
             "needs a safe_state of off or on for that channel (it is hold)");
    }
  }
  if (n["on_restart"]) {
    out->on_restart = getNamed(n["on_restart"], where + "on_restart", kOnRestartNames);
  }
  if (n["on_start"]) {
    const std::string text = get<std::string>(n["on_start"], where + "on_start", "safe or leave");
    if (text != "safe" && text != "leave" && text != "keep")
      fail(where + "on_start", "'" + text + "' is not safe or leave");
    if (text == "keep")  // the word before `leave` (on_restart's): deprecated, still taken
      deprecated->push_back(where + "on_start: 'keep' is deprecated, use 'leave' (the same)");
    out->on_start_safe = text == "safe";
  }
  if (n["heartbeat"])
    parseHeartbeat(n["heartbeat"], where + "heartbeat", &out->heartbeat_topic,
                   &out->heartbeat_timeout);
}

// share: {listen: "127.0.0.1:1502", read_only: false, allow: [127.0.0.1], max_clients: 4,
// max_queue: 16, idle_timeout: 60, broadcast_turnaround: 0.1, answer_within: 0.9}; every key
// optional.
void parseShare(const YAML::Node& n, ShareConfig* out) {
  if (!n.IsMap()) fail("share", show(n) + " is not a map {listen: HOST:PORT, allow: [...], ...}");
  checkKeys(n, "share/", kShareKeys);
  out->enabled = true;
  std::string error;
  if (n["listen"] && !parseListenAddress(get<std::string>(n["listen"], "share/listen", "HOST:PORT"),
                                         &out->server.host, &out->server.port, &error))
    fail("share/listen", error);
  if (n["read_only"]) out->read_only = getSwitch(n["read_only"], "share/read_only");
  if (n["allow"]) {
    const std::vector<std::string> allow = getNames(n["allow"], "share/allow");
    if (allow.empty()) fail("share/allow", "empty (no client could connect)");
    for (const std::string& entry : allow) {
      uint32_t network = 0, mask = 0;
      if (!parseAllowEntry(entry, &network, &mask, &error)) fail("share/allow", error);
    }
    out->server.allow = allow;
  }
  auto bounded = [&](const char* key, int low, int high, int* value) {
    if (!n[key]) return;
    *value = getInt(n[key], std::string("share/") + key);
    if (*value < low || *value > high)
      fail(std::string("share/") + key, std::to_string(*value) + " is outside " +
                                            std::to_string(low) + "-" + std::to_string(high));
  };
  bounded("max_clients", 1, 64, &out->server.max_clients);
  bounded("max_queue", 1, 1000, &out->max_queue);
  auto seconds = [&](const char* key, double high, const char* range, double* value) {
    if (!n[key]) return;
    *value = getNumber(n[key], std::string("share/") + key);
    if (!(*value >= 0 && *value <= high))
      fail(std::string("share/") + key, std::to_string(*value) + " s is outside " + range);
  };
  seconds("idle_timeout", 86400, "0-86400 s (0 = never)", &out->server.idle_timeout);
  seconds("broadcast_turnaround", kMaxBroadcastTurnaround, "0-1 s", &out->broadcast_turnaround);
  if (n["answer_within"]) {
    // Its lower bound, the longest transaction, depends on the link and the devices: the
    // gateway checks it at start (ShareGateway::start).
    out->answer_within = getNumber(n["answer_within"], "share/answer_within");
    if (!(out->answer_within >= kMinAnswerWithin && out->answer_within <= kMaxAnswerWithin))
      fail("share/answer_within", std::to_string(out->answer_within) + " s is outside 0.001-60 s");
  }
}

// The fail-safe of a generic device lives in its signals (safe_value); of the output keys it
// takes heartbeat and on_start, which act on those values. The rest would do nothing: refused.
void checkGenericFailsafe(const YAML::Node& n, const std::string& where,
                          const SignalMapConfig& map) {
  const std::map<std::string, std::string> not_for_generic = {
      {"safe_state", "give writable signals a safe_value instead"},
      {"command_timeout", "a generic device has no command topics"},
      {"on_restart", "a generic device has no restart detection"}};
  for (const auto& [key, why] : not_for_generic)
    if (n[key]) fail(where + key, "not for type generic (" + why + ")");
  bool any_safe = false;
  for (const SignalConfig& s : map.signals) any_safe = any_safe || s.safe_value.has_value();
  for (const char* key : {"heartbeat", "on_start"})
    if (n[key] && !any_safe)
      fail(where + key,
           "no signal has a safe_value, so it would do nothing (give writable signals one)");
}

// An unknown key names the keys of the device's own type only (a relay board's typo does not
// list the generic type's signal keys). Keys of another type get their own message below.
void checkDeviceKeys(const YAML::Node& n, const std::string& where) {
  std::string type;
  if (n["type"] && n["type"].IsScalar()) type = n["type"].Scalar();
  const bool generic = type == "generic";
  const std::vector<std::string> types = knownDeviceTypes();
  const bool known_type = std::find(types.begin(), types.end(), type) != types.end();
  std::vector<std::string> list;
  for (const auto& k : kDeviceKeys) {
    const bool signal_key =
        std::find(kSignalMapKeys.begin(), kSignalMapKeys.end(), k) != kSignalMapKeys.end();
    const bool common = k == "type" || k == "address" || k == "poll_rate" || k == "reply_delay";
    if (known_type && !common && signal_key != generic) continue;
    list.push_back(k);
  }
  for (const auto& kv : n) {
    const std::string key = kv.first.as<std::string>();
    if (!kDeviceKeys.count(key))
      fail(where + key,
           "unknown key (known keys" + (known_type ? " of " + type : "") + ": " + join(list) + ")");
  }
}

DeviceConfig parseDevice(const std::string& name, const YAML::Node& n,
                         const std::string& config_dir, std::vector<std::string>* deprecated) {
  const std::string where = "devices/" + name + "/";
  if (!isValidRosName(name))
    fail("devices/" + name,
         "device name is not a valid ROS name (a letter, then letters, digits or '_')");
  if (!n.IsMap()) fail("devices/" + name, show(n) + " is not a map of device settings");
  checkDeviceKeys(n, where);
  DeviceConfig d;
  d.name = name;
  if (!n["type"]) {
    fail(where + "type", "missing (one of " + join(knownDeviceTypes()) + ")");
  }
  d.type = get<std::string>(n["type"], where + "type", "a device type");
  if (!n["address"]) fail(where + "address", "missing (the device's slave address, 1-255)");
  d.address = getInt(n["address"], where + "address");
  if (n["poll_rate"]) d.poll_rate = getNumber(n["poll_rate"], where + "poll_rate");
  if (n["reply_delay"]) d.reply_delay = getNumber(n["reply_delay"], where + "reply_delay");
  if (n["outputs"]) d.outputs = getNames(n["outputs"], where + "outputs");
  if (n["inputs"]) d.inputs = getNames(n["inputs"], where + "inputs");
  if (d.type == "generic")
    d.generic = parseSignalMap(n, where, config_dir);
  else
    for (const auto& key : kSignalMapKeys)
      if (n[key]) fail(where + key, "only for type generic");
  const std::string problem = validateDeviceConfig(d);
  if (!problem.empty()) throw ConfigError{problem};
  if (d.type == "generic") checkGenericFailsafe(n, where, d.generic);
  parseFailsafe(n, where, outputNamesOf(d), &d.failsafe, deprecated);
  return d;
}

// A type that answers at a second address besides its own (DeviceDescriptor::also_answers: an
// LD58A08 also answers 0xFF): a device at that address on the same bus (an LC board at its
// factory address 255) answers the same frames, and the two replies garble on the line.
// Refused, with the way out.
void checkSecondAddresses(const std::vector<DeviceConfig>& devices) {
  for (const DeviceConfig& moved : devices) {
    std::string others;  // 'a', 'b': the devices that also answer at moved's address
    std::string other_type;
    for (const DeviceConfig& d : devices) {
      const auto* type = deviceClasses().find(d.type);
      if (&d == &moved || !type || type->type->also_answers != moved.address) continue;
      others += (others.empty() ? "'" : ", '") + d.name + "'";
      other_type = d.type;
    }
    if (others.empty()) continue;
    const std::string address = std::to_string(moved.address);
    fail("devices/" + moved.name + "/address",
         address + " collides with the " + other_type + " " + others + " on this bus: a " +
             other_type + " also answers at " + address +
             ", so both would answer and their replies garble. Move '" + moved.name + "' off " +
             address + " (modbus_rtu_commission set-address --type " + moved.type +
             " N, the device alone on the bus) and set devices/" + moved.name + "/address to N");
  }
}

void parse(const YAML::Node& root, BusConfig* out) {
  if (!root.IsMap()) fail("(root)", "the configuration is not a map of settings");
  checkKeys(root, "", with(kLinkKeys, kBusKeys));
  // The port first (its kind, registered with the links, parses it), then the line settings.
  readLink(root, &out->link);
  const std::string link_problem = validateLink(out->link, &out->link_target);
  if (!link_problem.empty()) throw ConfigError{link_problem};
  if (root["allow_raw_writes"])
    out->allow_raw_writes = getSwitch(root["allow_raw_writes"], "allow_raw_writes");
  if (root["role"]) {
    out->role = get<std::string>(root["role"], "role", "master or slave");
    if (out->role != "master") fail("role", "'" + out->role + "' is not master");
  }
  out->diagnostic_period = parseDiagnosticPeriod(root);
  if (root["publish_on_change"])
    out->publish_on_change = getSwitch(root["publish_on_change"], "publish_on_change");
  if (root["keep_alive"]) {
    out->keep_alive = getNumber(root["keep_alive"], "keep_alive");
    if (!(out->keep_alive >= 0.1 && out->keep_alive <= 3600))
      fail("keep_alive", numberText(out->keep_alive) + " s is outside 0.1-3600 s");
  }
  if (root["heartbeat"])
    parseHeartbeat(root["heartbeat"], "heartbeat", &out->heartbeat_topic, &out->heartbeat_timeout);
  if (root["shutdown_timeout"]) {
    out->shutdown_timeout = getNumber(root["shutdown_timeout"], "shutdown_timeout");
    if (!(out->shutdown_timeout >= 0 && out->shutdown_timeout <= kMaxShutdownTimeout))
      fail("shutdown_timeout",
           numberText(out->shutdown_timeout) +
               " s is outside 0-10 s (roslaunch sends SIGTERM 15 s after SIGINT, SIGKILL 2 s "
               "later; the bus thread's last transaction needs the rest)");
  }
  if (root["realtime_priority"]) {
    out->realtime_priority = getInt(root["realtime_priority"], "realtime_priority");
    if (out->realtime_priority < 0 || out->realtime_priority > 99)
      fail("realtime_priority", std::to_string(out->realtime_priority) +
                                    " is outside 0-99 (0 = off, 1-99 SCHED_FIFO priority)");
  }
  if (root["lock_memory"]) out->lock_memory = getSwitch(root["lock_memory"], "lock_memory");
  if (root["wire_log"]) {
    out->wire_log = get<std::string>(root["wire_log"], "wire_log", "a file path");
    if (out->wire_log.empty()) fail("wire_log", "'' is not a file path (leave it out for none)");
  }
  if (root["share"]) parseShare(root["share"], &out->share);
  std::string config_dir;  // where relative template paths start
  if (root["config_file"]) {
    const std::string file = get<std::string>(root["config_file"], "config_file", "a file path");
    const size_t slash = file.find_last_of('/');
    config_dir = slash == std::string::npos ? "." : file.substr(0, slash);
  }
  const YAML::Node devices = root["devices"];
  if (!devices) fail("devices", "missing (a map of device name -> settings)");
  if (!devices.IsMap() || devices.size() == 0)
    fail("devices", show(devices) + " is not a non-empty map of device name -> settings");
  std::map<int, std::string> by_address;
  for (const auto& kv : devices) {
    const std::string name = kv.first.as<std::string>();
    DeviceConfig d = parseDevice(name, kv.second, config_dir, &out->deprecated);
    auto [it, fresh] = by_address.emplace(d.address, name);
    if (!fresh)
      fail("devices/" + name + "/address",
           std::to_string(d.address) + " is already used by device '" + it->second + "'");
    out->devices.push_back(std::move(d));
  }
  checkSecondAddresses(out->devices);
}

}  // namespace

std::vector<std::string> configKeys() {
  std::vector<std::string> keys(kLinkKeys.begin(), kLinkKeys.end());
  keys.insert(keys.end(), kBusKeys.begin(), kBusKeys.end());
  for (const auto& k : kShareKeys) keys.push_back("share/" + k);
  for (const auto& k : kDeviceKeys) keys.push_back("devices/D/" + k);
  for (const auto& k : kSignalKeys) keys.push_back("devices/D/signals[]/" + k);
  const auto slave = slaveConfigKeys();
  keys.insert(keys.end(), slave.begin(), slave.end());
  return keys;
}

bool parseBusConfig(const YAML::Node& root, BusConfig* out, std::string* error) {
  return parseWith(parse, root, out, error);
}

}  // namespace modbus_rtu_driver
