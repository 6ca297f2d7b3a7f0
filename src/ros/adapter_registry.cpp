#include "modbus_rtu_driver/ros/adapter_registry.h"

namespace modbus_rtu_driver {

TypeRegistry<AdapterFactory>& adapterClasses() {
  static TypeRegistry<AdapterFactory> registry;  // built at its first use, by the first adapter
  return registry;
}

std::unique_ptr<DeviceAdapter> createAdapter(DeviceUnit& unit, BusScheduler& scheduler,
                                             const ros::NodeHandle& node) {
  const auto* entry = adapterClasses().find(unit.device().type());
  return entry ? entry->make(unit, scheduler, node) : nullptr;
}

}  // namespace modbus_rtu_driver
