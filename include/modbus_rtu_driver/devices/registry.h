// The device types the driver knows: each built-in descriptor (core/device_types.h) paired with
// its class. Adding a type: its descriptor, its class files and one line in registry.cpp (and
// one line in each of the ROS adapter and simulator registries; docs/adding_a_device_type.md).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "modbus_rtu_driver/devices/device.h"

namespace modbus_rtu_driver {

std::vector<std::string> knownDeviceTypes();
// Checks a device config (address range for the type, names, poll rate); empty when valid.
// The bus configuration runs it once, as it parses each device (config/bus_config.h).
std::string validateDeviceConfig(const DeviceConfig& config);
// The device for a config that passed validateDeviceConfig; null only for an unknown type.
std::unique_ptr<Device> createDevice(const DeviceConfig& config);
// The output channel names of a (valid) config, defaults filled in; empty for an unknown type.
std::vector<std::string> outputNamesOf(const DeviceConfig& config);

}  // namespace modbus_rtu_driver
