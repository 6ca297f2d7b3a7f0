// The LD58A08 as every layer knows it (docs/devices/ld58a08.md): digital outputs with PWM,
// addresses 0x01-0xF8 (its manual).
#pragma once

#include "modbus_rtu_driver/core/config/device_types.h"

namespace modbus_rtu_driver {

inline constexpr DeviceDescriptor kLd58a08Type{
    "ld58a08", 248, 8, 0, {1, 9600, Parity::kNone}, "docs/devices/ld58a08.md", 0xFF};

}  // namespace modbus_rtu_driver
