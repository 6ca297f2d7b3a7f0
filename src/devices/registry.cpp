#include "modbus_rtu_driver/devices/registry.h"

#include <cstdio>
#include <set>

#include "modbus_rtu_driver/core/config/config_yaml.h"
#include "modbus_rtu_driver/core/config/device_types.h"
#include "modbus_rtu_driver/core/config/number_text.h"

namespace modbus_rtu_driver {

namespace {

std::string checkNames(const std::string& key, const std::vector<std::string>& names,
                       size_t expected) {
  if (names.empty()) return {};
  if (names.size() != expected)
    return key + ": " + std::to_string(names.size()) + " names given, the device has " +
           std::to_string(expected);
  std::set<std::string> seen;
  for (const auto& n : names) {
    if (!isValidRosName(n))
      return key + ": '" + n + "' is not a valid ROS name (a letter, then letters, digits or '_')";
    if (!seen.insert(n).second) return key + ": '" + n + "' is given twice";
  }
  return {};
}

}  // namespace

TypeRegistry<DeviceFactory>& deviceClasses() {
  static TypeRegistry<DeviceFactory> registry;  // built at its first use, by the first type added
  return registry;
}

std::vector<std::string> outputNamesOf(const DeviceConfig& config) {
  const auto* t = deviceClasses().find(config.type);
  return t ? withDefaults(config.outputs, t->type->outputs, "out") : std::vector<std::string>{};
}

std::vector<std::string> knownDeviceTypes() {
  return deviceClasses().names();
}

std::string validateDeviceConfig(const DeviceConfig& c) {
  const std::string where = "devices/" + c.name + "/";
  const auto* found = deviceClasses().find(c.type);
  if (!found) {
    return where + "type: '" + c.type + "' is not a known device type (" +
           deviceClasses().nameList() + ")";
  }
  const DeviceDescriptor* t = found->type;
  if (c.address < 1 || c.address > t->max_address)
    return where + "address: " + std::to_string(c.address) + " is outside 1-" +
           std::to_string(t->max_address) + " for " + c.type;
  if (!validPollRate(c.poll_rate))
    return where + "poll_rate: " + numberText(c.poll_rate) + kPollRateRange;
  if (!(c.reply_delay >= 0.0 && c.reply_delay <= 1.0)) {
    return where + "reply_delay: " + numberText(c.reply_delay) + " s is outside 0-1 s";
  }
  std::string problem = checkNames(where + "outputs", c.outputs, t->outputs);
  if (problem.empty()) {
    if (t->inputs == 0 && !c.inputs.empty())
      problem = where + "inputs: " + c.type + " has no inputs";
    else
      problem = checkNames(where + "inputs", c.inputs, t->inputs);
  }
  return problem;
}

std::unique_ptr<Device> createDevice(const DeviceConfig& config) {
  const auto* t = deviceClasses().find(config.type);
  return t ? t->make(config) : nullptr;
}

}  // namespace modbus_rtu_driver
