// What every layer knows of a device type, written once: its name in the YAML, its address range,
// channel counts and factory settings. Each type's descriptor is in a header of its own
// (core/device_types/<type>.h); the driver's devices (devices/), their ROS adapters (ros/) and the
// simulated devices (sim/) each register their class for it (core/config/type_registry.h). The
// simulator stays independent of the driver's device classes, so the descriptors live here in the
// core, as plain data.
#pragma once

#include <cstddef>

#include "modbus_rtu_driver/core/config/link_config.h"

namespace modbus_rtu_driver {

struct FactorySettings {  // 0 where the type has none of its own
  int address;
  int baud;
  Parity parity;
};

struct DeviceDescriptor {
  const char* name;  // `type:` in the bus YAML
  int max_address;   // addresses 1..max_address
  size_t outputs;    // output channels (coils the driver switches)
  size_t inputs;     // digital input channels
  FactorySettings factory;
  const char* manual;  // where the register map comes from
  // An address it answers besides its own, 0 for none (an LD58A08 also answers 0xFF, "whoever
  // you are"): another device there on the same bus garbles every reply.
  int also_answers = 0;
};

}  // namespace modbus_rtu_driver
