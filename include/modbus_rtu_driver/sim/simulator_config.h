// The simulator's configuration (the devices on the line, their factory line settings, the pace)
// and its file, and the registry of the device types it may name: each simulated device adds
// itself from its own source file.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/config/type_registry.h"
#include "modbus_rtu_driver/sim/sim_device.h"
#include "modbus_rtu_driver/sim/sim_generic.h"

namespace modbus_rtu_driver {

struct SimulatorConfig {
  SimLineSettings factory;  // what the devices start at (baud, parity)
  bool pace = false;        // give frames their real wire time
  struct Entry {
    std::string type;
    int address;
    SimGenericConfig generic{};  // type generic: its signals and holes
  };
  std::vector<Entry> devices;
};

// The simulated types: each simulated device adds itself from its own source file
// (simDeviceClasses().add(...), core/config/type_registry.h).
using SimDeviceFactory = std::unique_ptr<SimDevice> (*)(const SimulatorConfig::Entry& entry,
                                                        SimLineSettings line);
TypeRegistry<SimDeviceFactory>& simDeviceClasses();
// The factory of a simulated device built from its address and line settings alone.
template <typename T>
std::unique_ptr<SimDevice> makeSimDeviceOf(const SimulatorConfig::Entry& entry,
                                           SimLineSettings line) {
  return std::make_unique<T>(static_cast<uint8_t>(entry.address), line);
}
// Builds the device an entry describes, listening at `line` (the factory settings); null for a
// type not simulated.
std::unique_ptr<SimDevice> makeSimDevice(const SimulatorConfig::Entry& entry, SimLineSettings line);
// The descriptor of a simulated type (its address range); null for a type not simulated.
const DeviceDescriptor* simDeviceType(const std::string& type);
std::string simDeviceTypeNames();  // "generic, lc_relay8, ld58a08, yespeed_pdu"

// False with a message naming the key when the YAML does not fit.
bool loadSimulatorConfig(const std::string& path, SimulatorConfig* out, std::string* error);
// `base_dir`: where a generic device's relative template path starts (the file's directory).
bool parseSimulatorConfig(const std::string& yaml, SimulatorConfig* out, std::string* error,
                          const std::string& base_dir = "");

}  // namespace modbus_rtu_driver
