// Configuration errors as a user reads them: numbers as people write them ("0.01 s", "nan",
// never "0.010000" or "-nan"), an unknown device key answered with the keys of that device's
// type only, and the key bus.launch adds (config_file) accepted by every role.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "bus_config_fixtures.h"
#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/core/config/slave_config.h"

using namespace modbus_rtu_driver;
using namespace modbus_rtu_driver::configtest;

namespace {

// A bus with one relay board: `device` adds to its settings, `bus` to the bus's.
std::string relays(const std::string& device, const std::string& bus = "") {
  return "{devices: {r: {type: lc_relay8, address: 1" + device + "}}" + bus + "}";
}

}  // namespace

// Issue #33 item 5: one set of on/off words everywhere: on/off, true/false, yes/no, 1/0 in any
// case. rosparam turns yes/no/on/off into booleans (true/false by the time the node reads
// them), so `{pump: yes}` was on while `0` was refused; a file read directly (these tests)
// and through rosparam now mean the same, and any other word is refused with the list.
TEST(ConfigMessages, OneSetOfOnOffWords) {
  for (const char* on : {"on", "true", "yes", "1", "ON", "Yes", "True"}) {
    const BusConfig c = parsed(relays(std::string(", safe_state: {out0: ") + on + "}"));
    EXPECT_EQ(c.devices[0].failsafe.safeStateOf(0), SafeState::kOn) << on;
  }
  for (const char* off : {"off", "false", "no", "0", "OFF", "No", "False"}) {
    const BusConfig c = parsed(relays(std::string(", safe_state: {out0: ") + off + "}"));
    EXPECT_EQ(c.devices[0].failsafe.safeStateOf(0), SafeState::kOff) << off;
  }
  EXPECT_EQ(parsed(relays(", safe_state: hold")).devices[0].failsafe.safeStateOf(0),
            SafeState::kLeave);
  EXPECT_EQ(parseError(relays(", safe_state: {out0: 2}")),
            "devices/r/safe_state/out0: '2' is not one of on, off, hold (on/off also as "
            "true/false, yes/no, 1/0)");
  EXPECT_EQ(parseError(relays(", safe_state: y")),
            "devices/r/safe_state: 'y' is not one of on, off, hold (on/off also as true/false, "
            "yes/no, 1/0)");
  // The true/false keys take the same words, and refuse the rest by the same list.
  EXPECT_TRUE(parsed(relays("", ", publish_on_change: 1")).publish_on_change);
  EXPECT_TRUE(parsed(relays("", ", allow_raw_writes: yes")).allow_raw_writes);
  EXPECT_FALSE(parsed(relays("", ", publish_on_change: off")).publish_on_change);
  EXPECT_EQ(parseError(relays("", ", publish_on_change: y")),
            "publish_on_change: 'y' is not one of on/off, true/false, yes/no, 1/0");
  EXPECT_EQ(parseError(relays("", ", low_latency: 2")),
            "low_latency: '2' is not one of on/off, true/false, yes/no, 1/0");
}

TEST(NumberText, AsPeopleWriteThem) {
  EXPECT_EQ(numberText(1.0), "1");
  EXPECT_EQ(numberText(0.05), "0.05");
  EXPECT_EQ(numberText(-0.0), "0");
  EXPECT_EQ(numberText(-std::nan("")), "nan");
  EXPECT_EQ(numberText(1.0 / 0.0), "inf");
  EXPECT_EQ(secondsText(5.0), "5 s");
  EXPECT_EQ(secondsText(0.4449), "0.4 s");
  EXPECT_EQ(secondsText(12.7), "13 s");
}

TEST(ConfigMessages, SecondsAsPeopleWriteThem) {
  EXPECT_EQ(parseError(relays("", ", heartbeat: {topic: hb, timeout: 0.01}")),
            "heartbeat/timeout: 0.01 s is outside 0.05-3600 s");
  EXPECT_EQ(parseError(relays("", ", keep_alive: 0.05")),
            "keep_alive: 0.05 s is outside 0.1-3600 s");
  EXPECT_EQ(
      parseError(relays("", ", shutdown_timeout: 10.5")),
      "shutdown_timeout: 10.5 s is outside 0-10 s (roslaunch sends SIGTERM 15 s after SIGINT, "
      "SIGKILL 2 s later; the bus thread's last transaction needs the rest)");
  EXPECT_EQ(parseError(relays("", ", diagnostic_period: 100")),
            "diagnostic_period: 100 s is outside 0.1-60 s");
  EXPECT_EQ(parseError(relays(", safe_state: off, command_timeout: 0.01")),
            "devices/r/command_timeout: 0.01 s is outside 0.05-3600 s (0 = none)");
}

TEST(ConfigMessages, NanIsNan) {
  EXPECT_EQ(parseError(relays(", poll_rate: .nan")),
            "devices/r/poll_rate: nan Hz is outside 0.001-1000 Hz (0 = never poll)");
  EXPECT_EQ(parseError(relays(", reply_delay: .nan")),
            "devices/r/reply_delay: nan s is outside 0-1 s");
  EXPECT_EQ(parseError(relays("", ", keep_alive: .nan")),
            "keep_alive: nan s is outside 0.1-3600 s");
}

TEST(ConfigMessages, AnUnknownKeyListsTheKeysOfThatDeviceTypeOnly) {
  EXPECT_EQ(parseError(relays(", safe_stat: off")),
            "devices/r/safe_stat: unknown key (known keys of lc_relay8: address, command_timeout, "
            "heartbeat, inputs, on_restart, on_start, outputs, poll_rate, reply_delay, "
            "safe_state, type)");
  EXPECT_EQ(parseError("devices: {m: {type: generic, address: 3, signal: []}}"),
            "devices/m/signal: unknown key (known keys of generic: address, max_gap, poll_rate, "
            "reply_delay, signals, template, type)");
  // A type nobody knows: every key, the type's own error comes from the type key.
  const std::string unknown = parseError("devices: {m: {type: relay, address: 3, x: 1}}");
  EXPECT_NE(unknown.find("devices/m/x: unknown key (known keys: address,"), std::string::npos)
      << unknown;
}

TEST(ConfigMessages, TheSlaveRoleTakesTheConfigFileBusLaunchSets) {
  YAML::Node root = YAML::Load("{role: slave, port: /dev/ttyS1, slave_id: 1}");
  root["config_file"] = "/somewhere/slave_dm500.yaml";
  SlaveConfig c;
  std::string error;
  EXPECT_TRUE(parseSlaveConfig(root, &c, &error)) << error;
}
