// The Yespeed power distribution unit as every layer knows it (docs/devices/yespeed_pdu.md):
// 8 relays and telemetry, the standard's addresses 1-247.
#pragma once

#include "modbus_rtu_driver/core/config/device_types.h"

namespace modbus_rtu_driver {

inline constexpr DeviceDescriptor kYespeedPduType{
    "yespeed_pdu", 247, 8, 0, {1, 9600, Parity::kNone}, "docs/devices/yespeed_pdu.md"};

}  // namespace modbus_rtu_driver
