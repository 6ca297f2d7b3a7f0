// The device types the driver knows: each type's class adds itself from its own source file
// (deviceClasses().add(...), core/config/type_registry.h), so a new type edits no table here
// (docs/adding_a_device_type.md).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/config/type_registry.h"
#include "modbus_rtu_driver/devices/device.h"

namespace modbus_rtu_driver {

using DeviceFactory = std::unique_ptr<Device> (*)(const DeviceConfig&);
TypeRegistry<DeviceFactory>& deviceClasses();
// The factory of a class built from its config alone.
template <typename T>
std::unique_ptr<Device> makeDevice(const DeviceConfig& config) {
  return std::make_unique<T>(config);
}

// The registered type names, alphabetical.
std::vector<std::string> knownDeviceTypes();
// Checks a device config (address range for the type, names, poll rate); empty when valid.
// The bus configuration runs it once, as it parses each device (node_config/bus_config.h).
std::string validateDeviceConfig(const DeviceConfig& config);
// The device for a config that passed validateDeviceConfig; null only for an unknown type.
std::unique_ptr<Device> createDevice(const DeviceConfig& config);
// The output channel names of a (valid) config, defaults filled in; empty for an unknown type.
std::vector<std::string> outputNamesOf(const DeviceConfig& config);

}  // namespace modbus_rtu_driver
