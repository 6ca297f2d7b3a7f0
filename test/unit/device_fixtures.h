// Fixtures of the device tests against a scripted transport: a device's settings by type and
// address, and the check a test ends with (every frame as scripted, the script used up).
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "modbus_rtu_driver/devices/device.h"
#include "scripted_transport.h"

namespace modbus_rtu_driver {
namespace devtest {

inline DeviceConfig config(const std::string& type, int address) {
  DeviceConfig c;
  c.name = "dev";
  c.type = type;
  c.address = address;
  return c;
}

}  // namespace devtest
}  // namespace modbus_rtu_driver

#define EXPECT_SCRIPT_DONE(bus)        \
  do {                                 \
    EXPECT_EQ((bus).mismatches(), ""); \
    EXPECT_TRUE((bus).usedUp());       \
  } while (0)
