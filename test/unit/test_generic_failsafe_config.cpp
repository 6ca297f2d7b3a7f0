// Issue 24/6: a generic device's fail-safe in the bus configuration. safe_value per writable
// signal (engineering units, checked as a write would be); heartbeat and on_start act on those
// values; the output keys that would do nothing on a generic device are refused by name.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "bus_config_fixtures.h"
#include "modbus_rtu_driver/node_config/bus_config.h"

using namespace modbus_rtu_driver;
using configtest::errorOf;

namespace {

// A generic device `m` with `signals` (a YAML list) and `more` device keys.
std::string device(const std::string& signals, const std::string& more = "") {
  return "devices: {m: {type: generic, address: 3, " + more + (more.empty() ? "" : ", ") +
         "signals: " + signals + "}}";
}

const char* kSpeed =
    "{name: speed, table: holding_register, address: 0, type: uint16, scale: 10, unit: rpm, "
    "writable: true, min: 0, max: 95";

std::string speed(const std::string& safe) {
  return std::string("[") + kSpeed + safe + "}]";
}

}  // namespace

TEST(GenericFailsafeConfig, SafeValuesAreParsedInEngineeringUnits) {
  BusConfig c;
  std::string error;
  const std::string yaml = device(
      "[{name: speed, table: holding_register, address: 0, type: int16, scale: 0.1, "
      "writable: true, min: -5, max: 5, safe_value: -2.5}, "
      "{name: run, table: coil, address: 0, writable: true, safe_value: off}, "
      "{name: lamp, table: coil, address: 1, writable: true, safe_value: on}, "
      "{name: horn, table: coil, address: 2, writable: true, safe_value: 1}, "
      "{name: free, table: coil, address: 3, writable: true}]",
      "on_start: safe, heartbeat: {topic: alive, timeout: 0.5}");
  ASSERT_TRUE(parseBusConfig(YAML::Load(yaml), &c, &error)) << error;
  const auto& s = c.devices[0].generic.signals;
  EXPECT_EQ(*s[0].safe_value, -2.5);
  EXPECT_EQ(*s[1].safe_value, 0.0);
  EXPECT_EQ(*s[2].safe_value, 1.0);
  EXPECT_EQ(*s[3].safe_value, 1.0);
  EXPECT_FALSE(s[4].safe_value.has_value());
  EXPECT_TRUE(c.devices[0].failsafe.on_start_safe);
  EXPECT_EQ(c.devices[0].failsafe.heartbeat_topic, "alive");
}

TEST(GenericFailsafeConfig, ASafeValueTheDeviceWouldNotGetIsRefusedWithItsRange) {
  EXPECT_EQ(errorOf(device(speed(", safe_value: 100"))),
            "devices/m/signals[0]/safe_value: 100 rpm is outside 0 to 95 rpm");
  // 95 rounds to raw 10, which the device holds as 100.
  EXPECT_EQ(errorOf(device(speed(", safe_value: 95"))),
            "devices/m/signals[0]/safe_value: 95 rpm would be written as 100 rpm (raw 10), "
            "outside 0 to 95 rpm");
  EXPECT_EQ(errorOf(device(speed(", safe_value: 90"))), "");
  EXPECT_EQ(errorOf(device("[{name: a, table: holding_register, address: 0, type: int16, "
                           "writable: true, safe_value: 40000}]")),
            "devices/m/signals[0]/safe_value: 40000 is raw 40000, outside what int16 holds "
            "(-32768 to 32767)");
  EXPECT_EQ(errorOf(device("[{name: a, table: holding_register, address: 0, safe_value: 1}]")),
            "devices/m/signals[0]/safe_value: only for writable signals (writable: true)");
  EXPECT_EQ(errorOf(device("[{name: a, table: coil, address: 0, writable: true, "
                           "safe_value: 2}]")),
            "devices/m/signals[0]/safe_value: '2' is not one of on/off, true/false, yes/no, 1/0 "
            "for the bit a");
  EXPECT_EQ(errorOf(device("[{name: a, table: holding_register, address: 0, writable: true, "
                           "safe_value: fast}]")),
            "devices/m/signals[0]/safe_value: 'fast' is not a number");
}

TEST(GenericFailsafeConfig, OutputKeysThatWouldDoNothingAreRefusedByName) {
  const std::string sig = speed(", safe_value: 0");
  EXPECT_EQ(errorOf(device(sig, "safe_state: off")),
            "devices/m/safe_state: not for type generic (give writable signals a safe_value "
            "instead)");
  EXPECT_EQ(errorOf(device(sig, "command_timeout: 1.0")),
            "devices/m/command_timeout: not for type generic (a generic device has no command "
            "topics)");
  EXPECT_EQ(errorOf(device(sig, "on_restart: restore")),
            "devices/m/on_restart: not for type generic (a generic device has no restart "
            "detection)");
  // heartbeat and on_start act on safe values: without any, they would do nothing.
  const std::string none = speed("");
  EXPECT_EQ(errorOf(device(none, "on_start: safe")),
            "devices/m/on_start: no signal has a safe_value, so it would do nothing (give "
            "writable signals one)");
  EXPECT_EQ(errorOf(device(none, "heartbeat: {topic: alive, timeout: 1}")),
            "devices/m/heartbeat: no signal has a safe_value, so it would do nothing (give "
            "writable signals one)");
  EXPECT_EQ(errorOf(device(sig, "on_start: safe, heartbeat: {topic: alive, timeout: 1}")), "");
  // The bus-wide heartbeat is the bus's: a generic device without safe values just has none.
  EXPECT_EQ(errorOf("heartbeat: {topic: alive, timeout: 1}\n" + device(none)), "");
}

TEST(GenericFailsafeConfig, TheExampleHasSafeValues) {
  const std::string file = std::string(REPO_DIR) + "/config/generic.yaml";
  YAML::Node root = YAML::LoadFile(file);
  root["config_file"] = file;
  BusConfig c;
  std::string error;
  ASSERT_TRUE(parseBusConfig(root, &c, &error)) << error;
  const DeviceConfig& drive = c.devices[2];
  EXPECT_EQ(*drive.generic.signals[0].safe_value, 0.0);  // speed_setpoint
  EXPECT_EQ(*drive.generic.signals[1].safe_value, 0.0);  // run: off
  EXPECT_EQ(drive.failsafe.heartbeat_topic, "drive_alive");
}
