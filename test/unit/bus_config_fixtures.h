// Fixtures of the bus configuration tests: a YAML text parsed as the node parses its
// parameters, expected to be refused (the error as the user reads it) or accepted.
#pragma once

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <string>

#include "modbus_rtu_driver/node_config/bus_config.h"

namespace modbus_rtu_driver {
namespace configtest {

// The error parseBusConfig gives for `yaml`; empty when it accepts it. For a test that checks
// either outcome (`EXPECT_EQ(errorOf(yaml), "")` for an accepted one).
inline std::string errorOf(const std::string& yaml) {
  BusConfig c;
  std::string error;
  return parseBusConfig(YAML::Load(yaml), &c, &error) ? "" : error;
}

// The error for a `yaml` the test expects refused: an accepted one fails the test here.
inline std::string parseError(const std::string& yaml) {
  const std::string error = errorOf(yaml);
  EXPECT_NE(error, "") << "accepted: " << yaml;
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
