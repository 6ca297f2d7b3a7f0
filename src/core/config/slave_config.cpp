#include "modbus_rtu_driver/core/config/slave_config.h"

#include <cctype>

#include "modbus_rtu_driver/core/config/config_yaml.h"

namespace modbus_rtu_driver {

namespace {

using namespace config;

// A table's size is keyed by the table's one name (coil: 64).
const std::set<std::string> kSlaveKeys = {"slave_id",         "coil",           "discrete_input",
                                          "holding_register", "input_register", "names"};

// Keys of earlier versions (coils:, holding_registers:) are refused with the one name to use.
void refuseFormerTableKeys(const YAML::Node& map, const std::string& where) {
  for (const auto& kv : map) {
    const std::string key = kv.first.as<std::string>();
    if (auto table = formerTableName(key))
      fail(where + key, std::string("the table is now named '") + tableName(*table) + "'");
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
  // config_file: bus.launch sets it for every role (the master's templates start there).
  refuseFormerTableKeys(root, "");
  checkKeys(root, "",
            with(with(kLinkKeys, {"role", "diagnostic_period", "config_file"}), kSlaveKeys));
  parseLink(root, &out->link);
  const std::string role = root["role"] ? get<std::string>(root["role"], "role", "slave") : "";
  if (role != "slave") fail("role", "'" + role + "' is not slave");
  if (out->link.port.empty()) fail("port", "must name a serial device such as /dev/ttyUSB0");
  if (out->link.port.find("://") != std::string::npos)
    fail("port", "'" + out->link.port + "': the slave role serves a serial port only");
  out->diagnostic_period = parseDiagnosticPeriod(root);
  if (!root["slave_id"]) fail("slave_id", "missing (the address this node answers, 1-247)");
  out->slave_id = getInt(root["slave_id"], "slave_id");
  if (out->slave_id < 1 || out->slave_id > 247)
    fail("slave_id", std::to_string(out->slave_id) + " is outside 1-247");
  out->coils = getTableSize(root, "coil", 64);
  out->discrete_inputs = getTableSize(root, "discrete_input", 64);
  out->holding_registers = getTableSize(root, "holding_register", 64);
  out->input_registers = getTableSize(root, "input_register", 64);
  const YAML::Node names = root["names"];
  if (names) {
    if (!names.IsMap()) fail("names", show(names) + " is not a map (coil, holding_register)");
    refuseFormerTableKeys(names, "names/");
    checkKeys(names, "names/", {"coil", "holding_register"});
    parseNames(names["coil"], "names/coil", out->coils, &out->coil_names);
    parseNames(names["holding_register"], "names/holding_register", out->holding_registers,
               &out->holding_names);
  }
}

}  // namespace

bool parseSlaveConfig(const YAML::Node& root, SlaveConfig* out, std::string* error) {
  return parseWith(parseSlave, root, out, error);
}

std::vector<std::string> slaveConfigKeys() {
  return std::vector<std::string>(kSlaveKeys.begin(), kSlaveKeys.end());
}

}  // namespace modbus_rtu_driver
