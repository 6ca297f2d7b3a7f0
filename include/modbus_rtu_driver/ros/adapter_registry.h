// Device type -> ROS adapter. A new device type adds its adapter file and one line here.
#pragma once

#include <memory>

#include "modbus_rtu_driver/ros/device_adapter.h"

namespace modbus_rtu_driver {

using AdapterFactory = std::unique_ptr<DeviceAdapter> (*)(std::shared_ptr<Device>, BusScheduler&,
                                                          const ros::NodeHandle&);

std::unique_ptr<DeviceAdapter> makeLd58a08Adapter(std::shared_ptr<Device>, BusScheduler&,
                                                  const ros::NodeHandle&);
std::unique_ptr<DeviceAdapter> makeLcRelay8Adapter(std::shared_ptr<Device>, BusScheduler&,
                                                   const ros::NodeHandle&);
std::unique_ptr<DeviceAdapter> makeYespeedPduAdapter(std::shared_ptr<Device>, BusScheduler&,
                                                     const ros::NodeHandle&);
std::unique_ptr<DeviceAdapter> makeGenericAdapter(std::shared_ptr<Device>, BusScheduler&,
                                                  const ros::NodeHandle&);

// Null for a type without an adapter.
std::unique_ptr<DeviceAdapter> createAdapter(std::shared_ptr<Device> device, BusScheduler& bus,
                                             const ros::NodeHandle& node);

}  // namespace modbus_rtu_driver
