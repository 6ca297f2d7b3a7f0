#include "modbus_rtu_driver/core/device_types.h"

namespace modbus_rtu_driver {

const DeviceDescriptor* findDeviceType(const std::string& name) {
  for (const DeviceDescriptor* t : kDeviceTypes)
    if (name == t->name) return t;
  return nullptr;
}

}  // namespace modbus_rtu_driver
