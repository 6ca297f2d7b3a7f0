// The simulator's configuration file and the registry of the device types it may name.
#include "modbus_rtu_driver/sim/simulator_config.h"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <set>
#include <sstream>

#include "modbus_rtu_driver/core/config/config_yaml.h"
#include "modbus_rtu_driver/core/config/link_config.h"

namespace modbus_rtu_driver {

namespace {

using config::fail;

// Throws config::ConfigError naming the key, as the node's parsers do (core/config/config_yaml.h).
void parseDevice(const YAML::Node& d, const std::string& where, const std::string& base_dir,
                 SimulatorConfig::Entry* e) {
  if (!d.IsMap()) fail(where, "not a map {type: ..., address: ...}");
  const bool generic = d["type"] && d["type"].IsScalar() && d["type"].Scalar() == "generic";
  std::set<std::string> keys = {"type", "address"};
  if (generic) {  // the node's keys (core/config/signal.h), and the simulator's own (sim_generic.h)
    keys.insert(kSignalMapKeys.begin(), kSignalMapKeys.end());
    keys.insert(kSimGenericKeys.begin(), kSimGenericKeys.end());
  }
  config::checkKeys(d, where + "/", keys);
  if (generic) parseSimGeneric(d, where + "/", base_dir, &e->generic);
  if (!d["type"] || !d["address"]) fail(where + (d["type"] ? "/address" : "/type"), "missing");
  e->type = config::get<std::string>(d["type"], where + "/type", "a device type");
  e->address = config::getInt(d["address"], where + "/address");
  const DeviceDescriptor* type = simDeviceType(e->type);
  if (!type)
    fail(where + "/type",
         "'" + e->type + "' is not a simulated type (" + simDeviceTypeNames() + ")");
  const int max = type->max_address;
  if (e->address < 1 || e->address > max)
    fail(where + "/address",
         std::to_string(e->address) + " is outside 1-" + std::to_string(max) + " for " + e->type);
}

void parseRoot(const YAML::Node& root, const std::string& base_dir, SimulatorConfig* out) {
  if (!root.IsMap())
    throw config::ConfigError{"the file is not a map of baud, parity, pace and devices"};
  config::checkKeys(root, "", {"baud", "parity", "pace", "devices"});
  SimulatorConfig& c = *out;
  if (root["baud"]) c.factory.baud = config::getInt(root["baud"], "baud");
  if (!isStandardBaud(c.factory.baud))
    fail("baud", std::to_string(c.factory.baud) + " is not a standard rate (1200-115200)");
  if (root["parity"]) {
    std::string problem;
    const auto parity = parseParity(
        config::get<std::string>(root["parity"], "parity", "none, even or odd"), &problem);
    if (!parity) fail("parity", problem);
    c.factory.parity = *parity;
  }
  if (root["pace"]) c.pace = config::getSwitch(root["pace"], "pace");
  if (!root["devices"] || !root["devices"].IsSequence())
    fail("devices", "missing or not a list of {type, address}");
  for (size_t i = 0; i < root["devices"].size(); ++i) {
    SimulatorConfig::Entry e;
    parseDevice(root["devices"][i], "devices[" + std::to_string(i) + "]", base_dir, &e);
    c.devices.push_back(e);
  }
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
  SimulatorConfig c;
  try {
    parseRoot(root, base_dir, &c);
  } catch (const config::ConfigError& e) {
    *error = e.message;
    return false;
  } catch (const YAML::Exception& e) {  // one the helpers do not turn into a ConfigError
    *error = std::string("configuration: ") + e.what();
    return false;
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

}  // namespace modbus_rtu_driver
