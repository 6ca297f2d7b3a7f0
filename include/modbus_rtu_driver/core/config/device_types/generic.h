// Any device described by its signals in the YAML (core/config/signal.h): no channels of its own,
// no factory settings (its manual's), the standard's addresses 1-247.
#pragma once

#include "modbus_rtu_driver/core/config/device_types.h"

namespace modbus_rtu_driver {

inline constexpr DeviceDescriptor kGenericType{
    "generic", 247, 0, 0, {0, 0, Parity::kNone}, "docs/ros_api.md (generic devices)"};

}  // namespace modbus_rtu_driver
