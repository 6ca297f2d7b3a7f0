// Device type -> ROS adapter. Each adapter adds itself from its own source file
// (adapterClasses().add(...), core/config/type_registry.h); a new type edits nothing here.
#pragma once

#include <memory>

#include "modbus_rtu_driver/core/config/type_registry.h"
#include "modbus_rtu_driver/ros/device_adapter.h"

namespace modbus_rtu_driver {

using AdapterFactory = std::unique_ptr<DeviceAdapter> (*)(std::shared_ptr<Device>, BusScheduler&,
                                                          const ros::NodeHandle&);
TypeRegistry<AdapterFactory>& adapterClasses();
// The factory of an adapter built from the device, the bus and the device's node handle.
template <typename T>
std::unique_ptr<DeviceAdapter> makeAdapter(std::shared_ptr<Device> device, BusScheduler& scheduler,
                                           const ros::NodeHandle& node) {
  return std::make_unique<T>(std::move(device), scheduler, node);
}

// Null for a type without an adapter.
std::unique_ptr<DeviceAdapter> createAdapter(std::shared_ptr<Device> device,
                                             BusScheduler& scheduler, const ros::NodeHandle& node);

}  // namespace modbus_rtu_driver
