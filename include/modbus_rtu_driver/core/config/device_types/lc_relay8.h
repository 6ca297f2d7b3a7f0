// The LC Technology 8-relay board as every layer knows it (docs/devices/lc_relay8.md): 8
// relays, 8 optocoupler inputs, factory address 255 (not a broadcast on this board).
#pragma once

#include "modbus_rtu_driver/core/config/device_types.h"

namespace modbus_rtu_driver {

inline constexpr DeviceDescriptor kLcRelay8Type{
    "lc_relay8", 255, 8, 8, {255, 9600, Parity::kNone}, "docs/devices/lc_relay8.md"};

}  // namespace modbus_rtu_driver
