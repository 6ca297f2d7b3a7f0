// Fixtures of the bus configuration tests: a YAML text parsed as the node parses its
// parameters, expected to be refused (the error as the user reads it) or accepted.
#pragma once

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <string>

#include "modbus_rtu_driver/config/bus_config.h"

namespace modbus_rtu_driver {
namespace configtest {

inline std::string parseError(const std::string& yaml) {
  BusConfig c;
  std::string error;
  EXPECT_FALSE(parseBusConfig(YAML::Load(yaml), &c, &error)) << yaml;
  return error;
}

inline BusConfig parsed(const std::string& yaml) {
  BusConfig c;
  std::string error;
  EXPECT_TRUE(parseBusConfig(YAML::Load(yaml), &c, &error)) << yaml << ": " << error;
  return c;
}

}  // namespace configtest
}  // namespace modbus_rtu_driver
