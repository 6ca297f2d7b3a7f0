#include "modbus_rtu_driver/ros/adapter_registry.h"

#include <cstring>

#include "modbus_rtu_driver/core/device_types.h"

namespace modbus_rtu_driver {

namespace {
struct Entry {
  const DeviceDescriptor* type;
  AdapterFactory make;
};
// One line per device type with a ROS interface.
const Entry kAdapters[] = {
    {&kLd58a08Type, makeLd58a08Adapter},
    {&kLcRelay8Type, makeLcRelay8Adapter},
    {&kYespeedPduType, makeYespeedPduAdapter},
    {&kGenericType, makeGenericAdapter},
};
}  // namespace

std::unique_ptr<DeviceAdapter> createAdapter(std::shared_ptr<Device> device, BusScheduler& bus,
                                             const ros::NodeHandle& node) {
  for (const auto& e : kAdapters)
    if (std::strcmp(e.type->name, device->type()) == 0) return e.make(std::move(device), bus, node);
  return nullptr;
}

}  // namespace modbus_rtu_driver
