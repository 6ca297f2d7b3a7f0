#include "modbus_rtu_driver/core/device_types.h"

namespace modbus_rtu_driver {

const DeviceDescriptor* findDeviceType(const std::string& name) {
  for (const DeviceDescriptor* t : kDeviceTypes)
    if (name == t->name) return t;
  return nullptr;
}

std::vector<std::string> deviceTypeNames() {
  std::vector<std::string> names;
  for (const DeviceDescriptor* t : kDeviceTypes) names.emplace_back(t->name);
  return names;
}

}  // namespace modbus_rtu_driver
