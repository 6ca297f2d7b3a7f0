// Line timing derived from the serial settings.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "modbus_rtu_driver/core/config/config_yaml.h"
#include "modbus_rtu_driver/core/config/link_config.h"
#include "modbus_rtu_driver/core/link/link_types.h"

using namespace modbus_rtu_driver;

TEST(LinkConfig, CharacterTimeAndFrameGap) {
  LinkConfig c;
  c.baud = 9600;
  EXPECT_EQ(bitsPerCharacter(c), 10);  // 8N1
  EXPECT_NEAR(characterTime(c), 10.0 / 9600, 1e-12);
  EXPECT_NEAR(frameGap(c), 3.5 * 10.0 / 9600, 1e-12);  // about 3.65 ms
  c.parity = Parity::kEven;
  EXPECT_EQ(bitsPerCharacter(c), 11);
  c.baud = 115200;
  EXPECT_DOUBLE_EQ(frameGap(c), 0.00175);  // fixed above 19200 baud by the spec
  c.min_gap = 0.01;
  EXPECT_DOUBLE_EQ(effectiveMinGap(c), 0.01);
}

TEST(LinkConfig, ValidationNamesTheField) {
  LinkConfig c;
  EXPECT_EQ(validateLinkConfig(c), "");
  c.baud = 12345;
  EXPECT_NE(validateLinkConfig(c).find("baud: 12345"), std::string::npos);
  c = LinkConfig{};
  c.stop_bits = 3;
  EXPECT_NE(validateLinkConfig(c).find("stop_bits"), std::string::npos);
  c = LinkConfig{};
  c.response_timeout = 0.0005;
  EXPECT_NE(validateLinkConfig(c).find("response_timeout"), std::string::npos);
  c = LinkConfig{};
  c.retries = 11;
  EXPECT_NE(validateLinkConfig(c).find("retries"), std::string::npos);
  c = LinkConfig{};
  c.late_reply_guard = 1.5;
  EXPECT_NE(validateLinkConfig(c).find("late_reply_guard: 1.5"), std::string::npos);
}

TEST(LinkConfig, ResponseTimeoutIsSizedFromTheBaudUnlessSet) {
  LinkConfig c;  // 9600 8N1: 10 bits a character
  EXPECT_EQ(c.response_timeout, 0.0);
  EXPECT_NEAR(effectiveResponseTimeout(c, 8), 8 * 10 / 9600.0 + 35 / 9600.0 + kTurnaroundAllowance,
              1e-12);
  c.baud = 115200;  // t3.5 fixed at 1.75 ms
  EXPECT_NEAR(effectiveResponseTimeout(c, 100), 1000 / 115200.0 + 0.00175 + kTurnaroundAllowance,
              1e-12);
  c.response_timeout = 0.3;
  EXPECT_EQ(effectiveResponseTimeout(c, 100), 0.3);
}

TEST(LinkConfig, Parity) {
  for (const auto& row : kParityNames) {
    EXPECT_EQ(parseParity(row.name, nullptr), row.value);
    EXPECT_EQ(parityName(row.value), row.name);
  }
  std::string error;
  EXPECT_FALSE(parseParity("mark", &error));
  EXPECT_EQ(error, "'mark' is not one of none, even, odd");
  EXPECT_FALSE(parseParity("O", &error)) << "one name: the letter is the 8N1 notation's";
  EXPECT_EQ(error, "'O' is not one of none, even, odd (write 'odd')");
  EXPECT_EQ(parityLetter(Parity::kEven), 'E');
  EXPECT_EQ(lineName(19200, Parity::kOdd), "19200 8O1");
}

// The port's forms are the registered link kinds' (core/link/link_types.h).
TEST(LinkConfig, PortForms) {
  LinkTarget a;
  std::string error;
  ASSERT_TRUE(parseLinkTarget("/dev/ttyUSB0", &a, &error));
  EXPECT_STREQ(a.type->name, "serial RTU");
  EXPECT_EQ(a.path, "/dev/ttyUSB0");
  ASSERT_TRUE(parseLinkTarget("tcp://192.168.1.7:502", &a, &error));
  EXPECT_STREQ(a.type->name, "Modbus TCP");
  EXPECT_EQ(a.host, "192.168.1.7");
  EXPECT_EQ(a.host_port, 502);
  ASSERT_TRUE(parseLinkTarget("rtu+tcp://gw-3.local:8899", &a, &error));
  EXPECT_STREQ(a.type->name, "RTU over TCP");
  EXPECT_EQ(a.host, "gw-3.local");
  ASSERT_TRUE(parseLinkTarget("tcp://[fd00::5]:502", &a, &error));
  EXPECT_EQ(a.host, "fd00::5");
  for (const char* bad : {"tcp://host", "tcp://:502", "tcp://host:0", "tcp://host:65536",
                          "rtu+tcp://host:50x", "mqtt://host:502", "tcp://a/b:502"}) {
    EXPECT_FALSE(parseLinkTarget(bad, &a, &error)) << bad;
    EXPECT_NE(error.find(std::string("'") + bad + "'"), std::string::npos) << error;
  }
  // An unknown scheme's message lists the registered ones, the device path and tcp:// first (a
  // kind added in its own files joins the list: no exact list here).
  EXPECT_FALSE(parseLinkTarget("mqtt://host:502", &a, &error));
  EXPECT_EQ(error.rfind("port: 'mqtt://host:502' is not a device path, tcp://", 0), 0u) << error;
  EXPECT_NE(error.find(" or "), std::string::npos) << error;
  EXPECT_NE(error.find("rtu+tcp://"), std::string::npos) << error;
  LinkConfig c;
  c.port = "tcp://host:99999";
  EXPECT_NE(validateLink(c, &a).find("tcp://HOST:PORT (port 1-65535)"), std::string::npos)
      << validateLink(c, &a);
  c.port = "";
  error = validateLink(c, &a);
  EXPECT_EQ(error.rfind("port: must name a serial device such as /dev/ttyUSB0, tcp://HOST:PORT", 0),
            0u)
      << error;
  EXPECT_NE(error.find("rtu+tcp://HOST:PORT"), std::string::npos) << error;
}

TEST(LinkConfig, NetworkAllowanceIsRangeChecked) {
  LinkConfig c;
  c.network_allowance = 10.5;
  EXPECT_NE(validateLinkConfig(c).find("network_allowance: 10.5"), std::string::npos);
  c.network_allowance = -0.1;
  EXPECT_NE(validateLinkConfig(c).find("network_allowance"), std::string::npos);
  c.network_allowance = 0;
  EXPECT_EQ(validateLinkConfig(c), "");
}

// Whole numbers in YAML: a value beyond int is refused before any cast (which would be
// undefined behaviour), a fraction is refused, hex is read.
TEST(ConfigYaml, WholeNumbers) {
  auto errorOf = [](const char* text) {
    try {
      config::getInt(YAML::Load(text), "baud");
    } catch (const config::ConfigError& e) {
      return e.message;
    }
    return std::string();
  };
  EXPECT_EQ(config::getInt(YAML::Load("0x0156"), "address"), 0x0156);
  EXPECT_EQ(config::getInt(YAML::Load("-7"), "offset"), -7);
  EXPECT_EQ(errorOf("1e12"), "baud: '1e12' is too large");
  EXPECT_EQ(errorOf("-3000000000"), "baud: '-3000000000' is too large");
  EXPECT_EQ(errorOf(".nan"), "baud: '.nan' is too large");
  EXPECT_EQ(errorOf("9600.5"), "baud: '9600.5' is not a whole number");
}
