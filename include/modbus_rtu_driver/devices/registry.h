// The device types the driver knows. Adding a type: one class file plus one line in
// registry.cpp (and, for its ROS interface, one line in the ROS adapter registry).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "modbus_rtu_driver/devices/device.h"

namespace modbus_rtu_driver {

std::vector<std::string> knownDeviceTypes();
// Null with a message naming the field when the type or the config does not fit.
std::unique_ptr<Device> createDevice(const DeviceConfig& config, std::string* error);
// Checks a device config (address range for the type, names, poll rate); empty when valid.
std::string validateDeviceConfig(const DeviceConfig& config);
// The output channel names of a (valid) config, defaults filled in; empty for an unknown type.
std::vector<std::string> outputNamesOf(const DeviceConfig& config);

}  // namespace modbus_rtu_driver
