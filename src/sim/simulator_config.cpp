// The simulator's configuration file, the registry of the device types it may name, and its state
// file (what the devices store).
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>

#include "modbus_rtu_driver/core/config/link_config.h"
#include "modbus_rtu_driver/sim/simulator.h"

namespace modbus_rtu_driver {

namespace {

// A scalar of type T at `key`, or a message naming the key and what was there.
template <typename T>
bool scalar(const YAML::Node& node, const std::string& key, const char* what, T* out,
            std::string* error) {
  try {
    if (!node.IsScalar()) throw YAML::Exception(node.Mark(), "");
    *out = node.as<T>();
    return true;
  } catch (const YAML::Exception&) {
    std::ostringstream text;
    if (node.IsScalar())
      text << "'" << node.Scalar() << "'";
    else
      text << "a " << (node.IsSequence() ? "list" : node.IsMap() ? "map" : "null");
    *error = key + ": " + text.str() + " is not " + what;
    return false;
  }
}

bool onlyKeys(const YAML::Node& map, const std::set<std::string>& allowed, const std::string& where,
              std::string* error) {
  for (const auto& kv : map) {
    const std::string key = kv.first.as<std::string>("");
    if (allowed.count(key)) continue;
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    *error = where + key + ": unknown key (expected " + list + ")";
    return false;
  }
  return true;
}

bool parseDevice(const YAML::Node& d, const std::string& where, const std::string& base_dir,
                 SimulatorConfig::Entry* e, std::string* error) {
  if (!d.IsMap()) {
    *error = where + ": not a map {type: ..., address: ...}";
    return false;
  }
  const bool generic = d["type"] && d["type"].IsScalar() && d["type"].Scalar() == "generic";
  std::set<std::string> keys = {"type", "address"};
  if (generic) {  // the node's keys (core/config/signal.h), and the simulator's own (sim_generic.h)
    keys.insert(kSignalMapKeys.begin(), kSignalMapKeys.end());
    keys.insert(kSimGenericKeys.begin(), kSimGenericKeys.end());
  }
  if (!onlyKeys(d, keys, where + "/", error)) return false;
  if (generic && !parseSimGeneric(d, where + "/", base_dir, &e->generic, error)) return false;
  if (!d["type"] || !d["address"]) {
    *error = where + (d["type"] ? "/address" : "/type") + ": missing";
    return false;
  }
  if (!scalar(d["type"], where + "/type", "a device type", &e->type, error) ||
      !scalar(d["address"], where + "/address", "a number", &e->address, error))
    return false;
  const DeviceDescriptor* type = simDeviceType(e->type);
  if (!type) {
    *error =
        where + "/type: '" + e->type + "' is not a simulated type (" + simDeviceTypeNames() + ")";
    return false;
  }
  const int max = type->max_address;
  if (e->address < 1 || e->address > max) {
    *error = where + "/address: " + std::to_string(e->address) + " is outside 1-" +
             std::to_string(max) + " for " + e->type;
    return false;
  }
  return true;
}

}  // namespace

TypeRegistry<SimDeviceFactory>& simDeviceClasses() {
  static TypeRegistry<SimDeviceFactory> registry;  // built at its first use, by the first type
  return registry;
}

std::unique_ptr<SimDevice> makeSimDevice(const SimulatorConfig::Entry& entry,
                                         SimLineSettings line) {
  const auto* t = simDeviceClasses().find(entry.type);
  return t ? t->make(entry, line) : nullptr;
}

const DeviceDescriptor* simDeviceType(const std::string& type) {
  const auto* t = simDeviceClasses().find(type);
  return t ? t->type : nullptr;
}

std::string simDeviceTypeNames() {
  return simDeviceClasses().nameList();
}

bool parseSimulatorConfig(const std::string& yaml, SimulatorConfig* out, std::string* error,
                          const std::string& base_dir) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    *error = std::string("not valid YAML: ") + e.what();
    return false;
  }
  if (!root.IsMap()) {
    *error = "the file is not a map of baud, parity, pace and devices";
    return false;
  }
  if (!onlyKeys(root, {"baud", "parity", "pace", "devices"}, "", error)) return false;
  SimulatorConfig c;
  if (root["baud"] && !scalar(root["baud"], "baud", "a number", &c.factory.baud, error))
    return false;
  if (!isStandardBaud(c.factory.baud)) {
    *error = "baud: " + std::to_string(c.factory.baud) + " is not a standard rate (1200-115200)";
    return false;
  }
  if (root["parity"]) {
    std::string text;
    if (!scalar(root["parity"], "parity", "none, even or odd", &text, error)) return false;
    std::string problem;
    const auto parity = parseParity(text, &problem);
    if (!parity) {
      *error = "parity: " + problem;
      return false;
    }
    c.factory.parity = *parity;
  }
  if (root["pace"] && !scalar(root["pace"], "pace", "true or false", &c.pace, error)) return false;
  if (!root["devices"] || !root["devices"].IsSequence()) {
    *error = "devices: missing or not a list of {type, address}";
    return false;
  }
  for (size_t i = 0; i < root["devices"].size(); ++i) {
    SimulatorConfig::Entry e;
    if (!parseDevice(root["devices"][i], "devices[" + std::to_string(i) + "]", base_dir, &e, error))
      return false;
    c.devices.push_back(e);
  }
  *out = c;
  return true;
}

bool loadSimulatorConfig(const std::string& path, SimulatorConfig* out, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = "cannot read the file";
    return false;
  }
  std::stringstream text;
  text << in.rdbuf();
  const size_t slash = path.find_last_of('/');
  return parseSimulatorConfig(text.str(), out, error,
                              slash == std::string::npos ? "." : path.substr(0, slash));
}

// Written only when it changed, through a temporary file, so a crash never leaves half a file.
void Simulator::saveState() {
  if (options_.state_file.empty()) return;
  YAML::Node root;
  for (auto& d : devices_) {
    YAML::Node n;
    n["type"] = d->type();
    d->saveState(n);
    root["devices"].push_back(n);
  }
  YAML::Emitter emitter;
  emitter << root;
  const std::string text = std::string(emitter.c_str()) + "\n";
  if (text == state_text_) return;
  const std::string tmp = options_.state_file + ".tmp";
  std::ofstream(tmp) << text;
  if (std::rename(tmp.c_str(), options_.state_file.c_str()) == 0) state_text_ = text;
}

// Devices are matched by index and type; a device whose entry does not fit keeps the config.
void Simulator::loadState(SimClock::time_point now) {
  if (options_.state_file.empty() || access(options_.state_file.c_str(), R_OK) != 0) return;
  try {
    const YAML::Node root = YAML::LoadFile(options_.state_file);
    const YAML::Node list = root["devices"];
    for (size_t i = 0; list.IsSequence() && i < devices_.size() && i < list.size(); ++i)
      if (list[i]["type"].as<std::string>("") == devices_[i]->type())
        devices_[i]->loadState(list[i], now);
  } catch (const YAML::Exception& e) {
    std::fprintf(stderr, "ignoring the state file %s: %s\n", options_.state_file.c_str(), e.what());
  }
}

}  // namespace modbus_rtu_driver
