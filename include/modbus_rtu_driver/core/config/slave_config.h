// The slave role's configuration (the node serves a Modbus master such as the DM500), checked
// key by key.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/config/link_config.h"

namespace YAML {
class Node;
}

namespace modbus_rtu_driver {

// Slave role: the node serves a Modbus master (such as the DM500 controller).
struct SlaveConfig {
  LinkConfig link;
  int slave_id = 1;     // 1-247
  uint16_t coils = 64;  // size of each table the master may use, 0-10000
  uint16_t discrete_inputs = 64;
  uint16_t holding_registers = 64;
  uint16_t input_registers = 64;
  double diagnostic_period = 1.0;                 // s
  std::map<uint16_t, std::string> coil_names;     // address -> ROS name
  std::map<uint16_t, std::string> holding_names;  // address -> ROS name
};

// False with one message naming the key, the value and what is allowed.
bool parseSlaveConfig(const YAML::Node& root, SlaveConfig* out, std::string* error);
// The keys the slave role accepts beside the link's (for documentation checks).
std::vector<std::string> slaveConfigKeys();

}  // namespace modbus_rtu_driver
