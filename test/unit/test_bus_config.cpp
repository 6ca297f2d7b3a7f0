// The bus configuration: defaults, and one clear message naming the key for each bad value.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "bus_config_fixtures.h"
#include "modbus_rtu_driver/core/config/config_yaml.h"
#include "modbus_rtu_driver/core/config/slave_config.h"
#include "modbus_rtu_driver/node_config/bus_config.h"

using namespace modbus_rtu_driver;
using configtest::errorOf;

namespace {

const char* kGood = R"(
port: /dev/ttyUSB0
baud: 9600
parity: none
data_bits: 8
stop_bits: 1
response_timeout: 0.5
retries: 1
devices:
  relays:
    type: lc_relay8
    address: 254          # not 255: the LD58A08 below answers at 0xFF too
    poll_rate: 10.0
    outputs: [pump, valve, lamp, fan, out4, out5, out6, out7]
    inputs: [door, estop, in2, in3, in4, in5, in6, in7]
  pwm_board: {type: ld58a08, address: 1, poll_rate: 5.0}
  pdu: {type: yespeed_pdu, address: 2, poll_rate: 2.0}
)";

// kGood with one line replaced.
std::string replaced(const std::string& from, const std::string& to) {
  std::string s = kGood;
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

}  // namespace

TEST(BusConfig, TheIssueExampleParses) {
  BusConfig c;
  std::string error;
  ASSERT_TRUE(parseBusConfig(YAML::Load(kGood), &c, &error)) << error;
  EXPECT_EQ(c.link.port, "/dev/ttyUSB0");
  EXPECT_EQ(c.link.baud, 9600);
  EXPECT_EQ(c.link.parity, Parity::kNone);
  ASSERT_EQ(c.devices.size(), 3u);
  EXPECT_EQ(c.devices[0].name, "relays");  // document order is kept
  EXPECT_EQ(c.devices[0].type, "lc_relay8");
  EXPECT_EQ(c.devices[0].address, 254);
  EXPECT_DOUBLE_EQ(c.devices[0].poll_rate, 10.0);
  EXPECT_EQ(c.devices[0].outputs[0], "pump");
  EXPECT_EQ(c.devices[0].inputs[1], "estop");
  EXPECT_EQ(c.devices[2].type, "yespeed_pdu");
}

TEST(BusConfig, MissingOptionalKeysTakeDefaults) {
  BusConfig c;
  std::string error;
  ASSERT_TRUE(
      parseBusConfig(YAML::Load("devices: {r: {type: lc_relay8, address: 255}}"), &c, &error))
      << error;
  EXPECT_EQ(c.link.port, "/dev/ttyUSB0");
  EXPECT_EQ(c.link.baud, 9600);
  EXPECT_EQ(c.link.data_bits, 8);
  EXPECT_EQ(c.link.stop_bits, 1);
  EXPECT_DOUBLE_EQ(c.link.response_timeout, 0.0);  // sized from the baud
  EXPECT_DOUBLE_EQ(c.link.late_reply_guard, 0.1);
  EXPECT_EQ(c.link.retries, 1);
  EXPECT_DOUBLE_EQ(c.devices[0].poll_rate, 1.0);
  EXPECT_TRUE(c.devices[0].outputs.empty());
}

struct BadCase {
  const char* from;
  const char* to;
  std::vector<std::string> words;  // must all appear in the one error message
};

TEST(BusConfig, AnLd58a08MayHaveAddress248) {
  EXPECT_EQ(errorOf(replaced("address: 1,", "address: 248,")), "") << "its manual: 1-248";
}

TEST(BusConfig, EachBadValueIsNamed) {
  const std::vector<BadCase> cases = {
      {"baud: 9600", "baud: 9601", {"baud", "9601", "115200"}},
      {"baud: 9600", "baud: fast", {"baud", "fast"}},
      {"parity: none", "parity: mark", {"parity", "mark", "none, even, odd"}},
      {"data_bits: 8", "data_bits: 9", {"data_bits", "9"}},
      {"stop_bits: 1", "stop_bits: 3", {"stop_bits", "3"}},
      {"response_timeout: 0.5", "response_timeout: 0.0001", {"response_timeout"}},
      {"response_timeout: 0.5", "response_timeout: -1", {"response_timeout", "0.001-10"}},
      {"retries: 1", "retries: -1", {"retries", "-1"}},
      {"port: /dev/ttyUSB0", "port: ''", {"port"}},
      {"port: /dev/ttyUSB0", "port: /dev/ttyUSB0\ncolour: red", {"colour", "unknown key"}},
      {"type: lc_relay8", "type: ld99", {"devices/relays/type", "ld99"}},
      {"address: 254", "address: 256", {"devices/relays/address", "256"}},
      {"address: 254", "address: 0", {"devices/relays/address", "0"}},
      {"address: 1,", "address: 249,", {"devices/pwm_board/address", "249", "1-248"}},
      {"address: 2,", "address: 248,", {"devices/pdu/address", "248", "1-247"}},
      {"address: 2,", "address: 1,", {"devices/pdu/address", "already used", "pwm_board"}},
      {"poll_rate: 10.0", "poll_rate: -2", {"devices/relays/poll_rate", "-2"}},
      // Issue #32 item 15: 1/rate overflowed the scheduler's nanosecond clock.
      {"poll_rate: 10.0",
       "poll_rate: 1.0e-10",
       {"devices/relays/poll_rate", "1e-10", "0.001-1000"}},
      {"poll_rate: 10.0", "poll_rate: 0.0009", {"devices/relays/poll_rate", "0.001-1000 Hz"}},
      {"port: /dev/ttyUSB0",
       "port: /dev/ttyUSB0\nrealtime_priority: 100",
       {"realtime_priority", "100", "0-99"}},
      {"port: /dev/ttyUSB0",
       "port: /dev/ttyUSB0\nrealtime_priority: high",
       {"realtime_priority", "high"}},
      {"port: /dev/ttyUSB0", "port: /dev/ttyUSB0\nlock_memory: maybe", {"lock_memory", "maybe"}},
      {"port: /dev/ttyUSB0", "port: /dev/ttyUSB0\nwire_log: ''", {"wire_log", "file path"}},
      {"port: /dev/ttyUSB0", "port: /dev/ttyUSB0\nwire_log: [a]", {"wire_log"}},
      {"  relays:", "  bad-name:", {"bad-name", "ROS name"}},
      {"[pump, valve,", "[pump, 2valve,", {"devices/relays/outputs", "2valve"}},
      {"[pump, valve,", "[pump, pump,", {"devices/relays/outputs", "pump"}},
      {"[door, estop, in2, in3, in4, in5, in6, in7]", "[door]", {"devices/relays/inputs", "8"}},
      {"    poll_rate: 10.0",
       "    poll_rate: 10.0\n    colour: red",
       {"devices/relays/colour", "unknown key"}},
  };
  for (const auto& c : cases) {
    const std::string error = errorOf(replaced(c.from, c.to));
    ASSERT_FALSE(error.empty()) << c.to;
    for (const auto& w : c.words)
      EXPECT_NE(error.find(w), std::string::npos) << c.to << " -> " << error;
  }
}

TEST(BusConfig, MissingRequiredKeys) {
  EXPECT_NE(errorOf("port: /dev/ttyS0").find("devices"), std::string::npos);
  EXPECT_NE(errorOf("devices: {r: {address: 3}}").find("devices/r/type"), std::string::npos);
  EXPECT_NE(errorOf("devices: {r: {type: ld58a08}}").find("devices/r/address"), std::string::npos);
  EXPECT_NE(errorOf("devices: {}").find("devices"), std::string::npos);
  EXPECT_NE(errorOf("- a\n- b").find("not a map"), std::string::npos);
}

TEST(BusConfig, RosNames) {
  EXPECT_TRUE(isValidRosName("pump"));
  EXPECT_TRUE(isValidRosName("out_7"));
  EXPECT_FALSE(isValidRosName("7out"));
  EXPECT_FALSE(isValidRosName("a-b"));
  EXPECT_FALSE(isValidRosName(""));
  EXPECT_FALSE(isValidRosName("a/b"));
}

TEST(BusConfig, EveryKeyIsDocumentedAndEveryExampleParses) {
  std::ifstream doc(std::string(REPO_DIR) + "/docs/ros_api.md");
  std::stringstream text;
  text << doc.rdbuf();
  ASSERT_FALSE(text.str().empty());
  for (const auto& key : configKeys())
    EXPECT_NE(text.str().find("`" + key + "`"), std::string::npos)
        << key << " is accepted by the code but missing from docs/ros_api.md";
  // Every bus example in config/ (the simulator's own files aside: test_sim_state), loaded as
  // bus.launch loads it: config_file set, where relative template paths start. A new example is
  // checked without an edit here.
  int examples = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(REPO_DIR) + "/config")) {
    const std::string file = entry.path().filename().string();
    if (entry.path().extension() != ".yaml" || file.rfind("simulator", 0) == 0) continue;
    ++examples;
    YAML::Node root = YAML::LoadFile(entry.path().string());
    root["config_file"] = entry.path().string();
    std::string error;
    bool ok = false;
    if (root["role"] && root["role"].as<std::string>() == "slave") {
      SlaveConfig c;
      ok = parseSlaveConfig(root, &c, &error);
    } else {
      BusConfig c;
      ok = parseBusConfig(root, &c, &error);
    }
    EXPECT_TRUE(ok) << file << ": " << error;
  }
  EXPECT_GE(examples, 7) << "bus_example, demo, generic, lc_relay8, ld58a08, slave_dm500, "
                            "yespeed_pdu at least";
}

TEST(BusConfig, ShareKeysWithDefaultsAndRanges) {
  BusConfig c;
  std::string error;
  ASSERT_TRUE(parseBusConfig(YAML::Load(kGood), &c, &error)) << error;
  EXPECT_FALSE(c.share.enabled);  // off unless configured
  const std::string shared =
      replaced("retries: 1", "retries: 1\nshare: {listen: \"0.0.0.0:5020\", read_only: true}");
  ASSERT_TRUE(parseBusConfig(YAML::Load(shared), &c, &error)) << error;
  EXPECT_TRUE(c.share.enabled);
  EXPECT_EQ(c.share.server.host, "0.0.0.0");
  EXPECT_EQ(c.share.server.port, 5020);
  EXPECT_TRUE(c.share.read_only);
  EXPECT_EQ(c.share.server.allow, std::vector<std::string>{"127.0.0.1"});  // localhost only
  EXPECT_EQ(c.share.server.max_clients, 4);
  EXPECT_EQ(c.share.max_queue, 16);
  ASSERT_TRUE(
      parseBusConfig(YAML::Load(replaced("retries: 1", "retries: 1\nshare: {}")), &c, &error));
  EXPECT_EQ(c.share.server.host, "127.0.0.1");
  EXPECT_EQ(c.share.server.port, 1502);
  auto shareError = [](const std::string& share) {
    return errorOf(replaced("retries: 1", "retries: 1\nshare: " + share));
  };
  EXPECT_NE(shareError("{listen: \"localhost:1502\"}").find("share/listen"), std::string::npos);
  EXPECT_NE(shareError("{listen: \"127.0.0.1:0\"}").find("1-65535"), std::string::npos);
  EXPECT_NE(shareError("{allow: [10.0.0.0/40]}").find("share/allow"), std::string::npos);
  EXPECT_NE(shareError("{allow: []}").find("share/allow: empty"), std::string::npos);
  EXPECT_NE(shareError("{max_clients: 0}").find("share/max_clients: 0 is outside 1-64"),
            std::string::npos);
  EXPECT_NE(shareError("{max_queue: 1001}").find("share/max_queue: 1001 is outside 1-1000"),
            std::string::npos);
  EXPECT_NE(shareError("{read_only: maybe}").find("share/read_only"), std::string::npos);
  EXPECT_NE(shareError("{port: 1502}").find("share/port"), std::string::npos);
  EXPECT_NE(shareError("true").find("share"), std::string::npos);
}

// Issue 24/8: an LD58A08 answers at 0xFF too, so an LC board at its factory address 255 on the
// same bus collides with it. Refused with the devices, the key and the way out named; an LC
// board at 255 without an LD58A08, or elsewhere beside one, is fine.
TEST(BusConfig, AnLcBoardAt255BesideAnLd58a08IsRefused) {
  const std::string error = errorOf(replaced("address: 254 ", "address: 255 "));
  EXPECT_EQ(error.rfind("devices/relays/address: 255 collides with the ld58a08 'pwm_board'", 0), 0u)
      << error;
  EXPECT_NE(error.find("Move 'relays' off 255 (modbus_rtu_commission set-address --type lc_relay8"),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("set devices/relays/address"), std::string::npos) << error;
  EXPECT_EQ(errorOf("devices: {r: {type: lc_relay8, address: 255}, p: {type: yespeed_pdu, "
                    "address: 2}}"),
            "");
  EXPECT_EQ(errorOf(kGood), "");
  // Whatever the order in the file.
  EXPECT_NE(errorOf("devices: {a: {type: ld58a08, address: 1}, b: {type: ld58a08, address: 2}, "
                    "r: {type: lc_relay8, address: 255}}")
                .find("devices/r/address: 255 collides with the ld58a08 'a', 'b'"),
            std::string::npos);
}
