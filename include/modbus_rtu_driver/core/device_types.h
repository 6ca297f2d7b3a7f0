// What every layer knows of each built-in device type, written once: its name in the YAML, its
// address range, channel counts and factory settings. The device registry (devices/), the ROS
// adapter registry (ros/), the simulator (sim/) and the commissioning tool (tools/) each pair
// these descriptors with their own class for the type; the simulator stays independent of the
// driver's device classes, so the descriptors live here in the core, as plain data.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace modbus_rtu_driver {

struct FactorySettings {  // 0 where the type has none of its own
  int address;
  int baud;
  char parity;  // 'N', 'E', 'O'
};

struct DeviceDescriptor {
  const char* name;  // `type:` in the bus YAML
  int max_address;   // addresses 1..max_address
  size_t outputs;    // output channels (coils the driver switches)
  size_t inputs;     // digital input channels
  FactorySettings factory;
  const char* manual;  // where the register map comes from
};

// Digital outputs with PWM. Addresses 0x01-0xF8 (its manual).
inline constexpr DeviceDescriptor kLd58a08Type{
    "ld58a08", 248, 8, 0, {1, 9600, 'N'}, "docs/devices/ld58a08.md"};
// 8 relays, 8 optocoupler inputs. Factory address 255 (not a broadcast on this board).
inline constexpr DeviceDescriptor kLcRelay8Type{
    "lc_relay8", 255, 8, 8, {255, 9600, 'N'}, "docs/devices/lc_relay8.md"};
// Power distribution unit: 8 relays, telemetry. The standard's 1-247.
inline constexpr DeviceDescriptor kYespeedPduType{
    "yespeed_pdu", 247, 8, 0, {1, 9600, 'N'}, "docs/devices/yespeed_pdu.md"};

// Any device described by its signals in the YAML (core/signal.h): no channels of its own, no
// factory settings (its manual's), the standard's 1-247.
inline constexpr DeviceDescriptor kGenericType{
    "generic", 247, 0, 0, {0, 0, 'N'}, "docs/ros_api.md (generic devices)"};

// Every type, in the order the docs list them.
inline constexpr const DeviceDescriptor* kDeviceTypes[] = {&kLd58a08Type, &kLcRelay8Type,
                                                           &kYespeedPduType, &kGenericType};

// Null for a name that is not a built-in type.
const DeviceDescriptor* findDeviceType(const std::string& name);

}  // namespace modbus_rtu_driver
