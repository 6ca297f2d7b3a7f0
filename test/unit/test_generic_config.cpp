// A generic device in the bus configuration: its keys, templates relative to config_file, the
// example config/generic.yaml, and generic keys refused on the other types.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "bus_config_fixtures.h"

using namespace modbus_rtu_driver;
using namespace modbus_rtu_driver::configtest;

TEST(GenericConfig, TheExampleParsesWithItsTemplates) {
  const std::string file = std::string(REPO_DIR) + "/config/generic.yaml";
  YAML::Node root = YAML::LoadFile(file);
  root["config_file"] = file;  // as bus.launch sets it
  BusConfig c;
  std::string error;
  ASSERT_TRUE(parseBusConfig(root, &c, &error)) << error;
  ASSERT_EQ(c.devices.size(), 3u);
  const DeviceConfig& climate = c.devices[0];
  EXPECT_EQ(climate.type, "generic");
  ASSERT_EQ(climate.generic.signals.size(), 4u);
  EXPECT_EQ(climate.generic.signals[0].name, "temperature");
  EXPECT_EQ(climate.generic.signals[2].address, 0x0103);  // hex in the template
  EXPECT_EQ(c.devices[1].generic.signals.size(), 10u);
  EXPECT_EQ(c.devices[2].generic.signals[0].address, 0x2000);
  EXPECT_EQ(c.devices[2].generic.signals[0].writeFunction(), 16);  // write_function: 16
  EXPECT_EQ(c.devices[2].generic.signals[1].writeFunction(), 5);   // a coil's default
  ASSERT_TRUE(c.devices[2].generic.signals[3].poll_rate.has_value());
  EXPECT_EQ(*c.devices[2].generic.signals[3].poll_rate, 20.0);
}

TEST(GenericConfig, ErrorsNameTheKey) {
  EXPECT_EQ(parseError("devices: {m: {type: generic, address: 3}}"),
            "devices/m/signals: missing (a list of signals, or template: FILE with one)");
  EXPECT_EQ(parseError("devices: {m: {type: generic, address: 3, template: t.yaml}}")
                .rfind("devices/m/template: 't.yaml' is relative", 0),
            0u);
  EXPECT_EQ(parseError("devices: {m: {type: generic, address: 3, signals: [{name: a, table: "
                       "coil, address: 0, type: int16}]}}"),
            "devices/m/signals[0]/type: int16 does not fit a coil (bits are bool)");
  EXPECT_EQ(parseError("devices: {p: {type: yespeed_pdu, address: 3, max_gap: 2}}"),
            "devices/p/max_gap: only for type generic");
  EXPECT_EQ(parseError("devices: {m: {type: generic, address: 248, signals: [{name: a, table: "
                       "coil, address: 0}]}}"),
            "devices/m/address: 248 is outside 1-247 for generic");
  EXPECT_EQ(parseError("devices: {m: {type: generic, address: 3, outputs: [a], signals: [{name: "
                       "a, table: coil, address: 0}]}}"),
            "devices/m/outputs: 1 names given, the device has 0");
  EXPECT_EQ(parseError("devices: {m: {type: generic, address: 3, signals: [{name: a, table: "
                       "holding_register, address: 0, type: float32, writable: true, "
                       "write_function: 6}]}}"),
            "devices/m/signals[0]/write_function: 6 (write single register) cannot write the 2 "
            "registers of float32; use 16 (write multiple registers)");
}
