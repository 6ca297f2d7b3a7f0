// Device type -> ROS adapter. Each adapter adds itself from its own source file
// (adapterClasses().add(...), core/config/type_registry.h); a new type edits nothing here.
#pragma once

#include <memory>

#include "modbus_rtu_driver/core/config/type_registry.h"
#include "modbus_rtu_driver/ros/device_adapter.h"

namespace modbus_rtu_driver {

using AdapterFactory = std::unique_ptr<DeviceAdapter> (*)(DeviceUnit&, BusScheduler&,
                                                          const ros::NodeHandle&);
TypeRegistry<AdapterFactory>& adapterClasses();
// The factory of an adapter built from the device's unit, the bus and the node's handle.
template <typename T>
std::unique_ptr<DeviceAdapter> makeAdapter(DeviceUnit& unit, BusScheduler& scheduler,
                                           const ros::NodeHandle& node) {
  return std::make_unique<T>(unit, scheduler, node);
}

// Null for a type without an adapter.
std::unique_ptr<DeviceAdapter> createAdapter(DeviceUnit& unit, BusScheduler& scheduler,
                                             const ros::NodeHandle& node);

}  // namespace modbus_rtu_driver
