// The configuration of one bus node (what the YAML in the node's private namespace says),
// checked key by key. ROS-free so every rule is unit-tested; the node converts its parameters
// to a YAML::Node and calls parseBusConfig.
#pragma once

#include <string>
#include <vector>

#include "modbus_rtu_driver/core/link_config.h"
#include "modbus_rtu_driver/devices/device.h"

namespace YAML {
class Node;
}

namespace modbus_rtu_driver {

struct BusConfig {
  LinkConfig link;
  std::string role = "master";     // master: the node polls devices; slave: a master polls the node
  double diagnostic_period = 1.0;  // s
  std::vector<DeviceConfig> devices;
};

// False with one message naming the key, the value and what is allowed; `out` is then undefined.
bool parseBusConfig(const YAML::Node& root, BusConfig* out, std::string* error);

// True when `name` is a valid ROS graph name segment: a letter, then letters, digits, '_'.
bool isValidRosName(const std::string& name);

}  // namespace modbus_rtu_driver
