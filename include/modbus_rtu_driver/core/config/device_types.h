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

// poll_rate (Hz) of a device or a generic signal: 0 = never polled, else 0.001-1000 Hz. The floor
// keeps the poll period (1/rate) inside the scheduler's nanosecond clock (1e-10 Hz overflowed it
// and flooded the line); one poll in 1000 s is slower than anything a robot logs.
constexpr double kMinPollRate = 0.001;
constexpr double kMaxPollRate = 1000.0;
constexpr const char* kPollRateRange = " Hz is outside 0.001-1000 Hz (0 = never poll)";
inline bool validPollRate(double hz) {
  return hz == 0.0 || (hz >= kMinPollRate && hz <= kMaxPollRate);
}

}  // namespace modbus_rtu_driver
