// Signals of generic devices (core/config/signal.h): decoding and encoding of every type and word
// order, the YAML rules (errors name the key) and templates.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "modbus_rtu_driver/core/config/config_yaml.h"
#include "modbus_rtu_driver/core/config/signal.h"

using namespace modbus_rtu_driver;

namespace {

double decode(SignalType t, WordOrder o, std::vector<uint16_t> words) {
  return decodeRaw(t, o, words.data());
}

// The message of the ConfigError that parsing `yaml` (a device map) throws; empty if none.
std::string parseError(const std::string& yaml, const std::string& base_dir = "") {
  try {
    parseSignalMap(YAML::Load(yaml), "devices/d/", base_dir);
  } catch (const config::ConfigError& e) {
    return e.message;
  }
  return "";
}

std::string oneSignal(const std::string& fields) {
  return "signals: [{name: x, " + fields + "}]";
}

}  // namespace

TEST(SignalCodec, SixteenBitTypes) {
  EXPECT_EQ(decode(SignalType::kUint16, WordOrder::kBig, {0xFF33}), 65331.0);
  EXPECT_EQ(decode(SignalType::kInt16, WordOrder::kBig, {0xFF33}), -205.0);  // XY-MD02: -20.5 C
  EXPECT_EQ(decode(SignalType::kBool, WordOrder::kBig, {1}), 1.0);
  EXPECT_EQ(encodeRaw(SignalType::kInt16, WordOrder::kBig, -205), std::vector<uint16_t>{0xFF33});
  EXPECT_EQ(encodeRaw(SignalType::kUint16, WordOrder::kBig, 65535), std::vector<uint16_t>{0xFFFF});
}

TEST(SignalCodec, ThirtyTwoBitTypesInBothWordOrders) {
  EXPECT_EQ(decode(SignalType::kUint32, WordOrder::kBig, {0x0001, 0x0002}), 65538.0);
  EXPECT_EQ(decode(SignalType::kUint32, WordOrder::kLittle, {0x0002, 0x0001}), 65538.0);
  EXPECT_EQ(decode(SignalType::kInt32, WordOrder::kBig, {0xFFFF, 0xFFFE}), -2.0);
  EXPECT_EQ(decode(SignalType::kInt32, WordOrder::kLittle, {0xFFFE, 0xFFFF}), -2.0);
  // 230.0f is 0x43660000 (an SDM120 voltage).
  EXPECT_EQ(decode(SignalType::kFloat32, WordOrder::kBig, {0x4366, 0x0000}), 230.0);
  EXPECT_EQ(decode(SignalType::kFloat32, WordOrder::kLittle, {0x0000, 0x4366}), 230.0);
  EXPECT_EQ(encodeRaw(SignalType::kFloat32, WordOrder::kBig, 230.0),
            (std::vector<uint16_t>{0x4366, 0x0000}));
  EXPECT_EQ(encodeRaw(SignalType::kFloat32, WordOrder::kLittle, -1.5),
            (std::vector<uint16_t>{0x0000, 0xBFC0}));
  EXPECT_EQ(encodeRaw(SignalType::kInt32, WordOrder::kBig, -2),
            (std::vector<uint16_t>{0xFFFF, 0xFFFE}));
  EXPECT_EQ(encodeRaw(SignalType::kUint32, WordOrder::kLittle, 65538),
            (std::vector<uint16_t>{0x0002, 0x0001}));
}

TEST(SignalCodec, SixtyFourBitTypes) {
  EXPECT_EQ(decode(SignalType::kUint64, WordOrder::kBig, {0, 0, 1, 0}), 65536.0);
  EXPECT_EQ(decode(SignalType::kUint64, WordOrder::kLittle, {0, 1, 0, 0}), 65536.0);
  EXPECT_EQ(decode(SignalType::kInt64, WordOrder::kBig, {0xFFFF, 0xFFFF, 0xFFFF, 0xFFFD}), -3.0);
  EXPECT_EQ(encodeRaw(SignalType::kInt64, WordOrder::kLittle, -3),
            (std::vector<uint16_t>{0xFFFD, 0xFFFF, 0xFFFF, 0xFFFF}));
  EXPECT_EQ(encodeRaw(SignalType::kUint64, WordOrder::kBig, 1e15),
            (std::vector<uint16_t>{0x0003, 0x8D7E, 0xA4C6, 0x8000}));
  EXPECT_EQ(decode(SignalType::kUint64, WordOrder::kBig, {0x0003, 0x8D7E, 0xA4C6, 0x8000}), 1e15);
}

TEST(SignalCodec, RangesAndSizes) {
  EXPECT_EQ(wordsOf(SignalType::kFloat32), 2);
  EXPECT_EQ(wordsOf(SignalType::kInt64), 4);
  EXPECT_EQ(rawMin(SignalType::kInt16), -32768.0);
  EXPECT_EQ(rawMax(SignalType::kUint32), 4294967295.0);
  EXPECT_EQ(rawMin(SignalType::kUint16), 0.0);
}

TEST(SignalYaml, ReadsEveryKey) {
  const auto m = parseSignalMap(YAML::Load(R"(
max_gap: 3
signals:
  - {name: t, table: input_register, address: 1, type: int16, scale: 0.1, unit: C}
  - {name: e, table: holding_register, address: 10, type: float32, word_order: little,
     scale: 2, offset: -1, writable: true, min: -5, max: 5, poll_rate: 20}
  - {name: relay, table: coil, address: 3, writable: true}
  - {name: door, table: discrete_input, address: 0}
)"),
                                "devices/d/", "");
  ASSERT_EQ(m.signals.size(), 4u);
  EXPECT_EQ(m.max_gap, 3);
  const SignalConfig& e = m.signals[1];
  EXPECT_EQ(e.table, Table::kHoldingRegister);
  EXPECT_EQ(e.address, 10);
  EXPECT_EQ(e.type, SignalType::kFloat32);
  EXPECT_EQ(e.word_order, WordOrder::kLittle);
  EXPECT_EQ(e.scale, 2.0);
  EXPECT_EQ(e.offset, -1.0);
  EXPECT_TRUE(e.writable);
  ASSERT_TRUE(e.min.has_value() && e.max.has_value() && e.poll_rate.has_value());
  EXPECT_EQ(*e.min, -5.0);
  EXPECT_EQ(*e.max, 5.0);
  EXPECT_EQ(*e.poll_rate, 20.0);
  EXPECT_FALSE(m.signals[0].poll_rate.has_value());
  EXPECT_EQ(m.signals[0].unit, "C");
  EXPECT_EQ(m.signals[2].type, SignalType::kBool);  // bits default to bool
  EXPECT_EQ(m.signals[3].table, Table::kDiscreteInput);
}

TEST(SignalYaml, ErrorsNameTheKey) {
  const std::string base = "devices/d/signals[0]/";
  EXPECT_EQ(parseError("max_gap: 1"),
            "devices/d/signals: missing (a list of signals, or "
            "template: FILE with one)");
  EXPECT_EQ(
      parseError(oneSignal("table: coil, address: 1, colour: red")).rfind(base + "colour:", 0), 0u);
  EXPECT_EQ(parseError(oneSignal("table: coils, address: 1")).rfind(base + "table:", 0), 0u);
  EXPECT_EQ(parseError(oneSignal("table: coil, address: 70000")).rfind(base + "address:", 0), 0u);
  EXPECT_EQ(parseError(oneSignal("table: coil, address: 1, type: uint16")).rfind(base + "type", 0),
            0u);
  EXPECT_EQ(parseError(oneSignal("table: holding_register, address: 1, type: bool"))
                .rfind(base + "type", 0),
            0u);
  EXPECT_EQ(parseError(oneSignal("table: input_register, address: 1, writable: true"))
                .rfind(base + "writable", 0),
            0u);
  EXPECT_EQ(parseError(oneSignal("table: holding_register, address: 1, word_order: big"))
                .rfind(base + "word_order", 0),
            0u);
  EXPECT_EQ(parseError(oneSignal("table: holding_register, address: 65535, type: uint32"))
                .rfind(base + "address", 0),
            0u);
  EXPECT_EQ(parseError(oneSignal("table: holding_register, address: 1, scale: 0"))
                .rfind(base + "scale", 0),
            0u);
  // min is in engineering units: 7000 / 0.1 does not fit int16.
  EXPECT_EQ(parseError(oneSignal("table: holding_register, address: 1, type: int16, scale: 0.1, "
                                 "writable: true, min: 7000"))
                .rfind(base + "min", 0),
            0u);
  EXPECT_EQ(parseError(oneSignal("table: holding_register, address: 1, writable: true, min: 5, "
                                 "max: 1"))
                .rfind(base + "min", 0),
            0u);
  EXPECT_EQ(
      parseError(oneSignal("table: input_register, address: 1, min: 1")).rfind(base + "min", 0),
      0u);
  EXPECT_EQ(parseError(oneSignal("table: input_register, address: 1, poll_rate: -1"))
                .rfind(base + "poll_rate", 0),
            0u);
  // Issue #32 item 15: a rate whose period overflows the scheduler's clock is refused by name.
  EXPECT_EQ(parseError(oneSignal("table: input_register, address: 1, poll_rate: 1.0e-10")),
            base + "poll_rate: 1e-10 Hz is outside 0.001-1000 Hz (0 = never poll)");
  EXPECT_EQ(parseError(oneSignal("table: input_register, address: 1, poll_rate: 0")), "");
  EXPECT_EQ(parseError("signals: [{name: 'a b', table: coil, address: 1}]").rfind(base + "name", 0),
            0u);
  EXPECT_EQ(
      parseError("signals: [{name: signals, table: coil, address: 1}]").rfind(base + "name", 0),
      0u);
  EXPECT_EQ(parseError("signals: [{name: a, table: holding_register, address: 1, type: uint32}, "
                       "{name: b, table: holding_register, address: 2}]"),
            "devices/d/signals: 'b' overlaps 'a' (holding_register 2)");
  EXPECT_EQ(parseError("signals: [{name: a, table: coil, address: 1}, {name: a, table: coil, "
                       "address: 2}]"),
            "devices/d/signals: 'a' is given twice");
  EXPECT_EQ(parseError("max_gap: 200\n" + oneSignal("table: coil, address: 1")),
            "devices/d/max_gap: 200 is outside 0-123");
}

TEST(SignalYaml, WriteFunctionDefaultsByTableAndWidthAndIsChecked) {
  const auto m = parseSignalMap(YAML::Load(R"(
signals:
  - {name: c, table: coil, address: 0, writable: true}
  - {name: c15, table: coil, address: 1, writable: true, write_function: 15}
  - {name: r, table: holding_register, address: 0, writable: true}
  - {name: r16, table: holding_register, address: 1, writable: true, write_function: 16}
  - {name: wide, table: holding_register, address: 2, type: int32, writable: true}
)"),
                                "devices/d/", "");
  ASSERT_EQ(m.signals.size(), 5u);
  EXPECT_EQ(m.signals[0].writeFunction(), 5);
  EXPECT_EQ(m.signals[1].writeFunction(), 15);
  EXPECT_EQ(m.signals[2].writeFunction(), 6);
  EXPECT_EQ(m.signals[3].writeFunction(), 16);
  EXPECT_EQ(m.signals[4].writeFunction(), 16);
  EXPECT_EQ(m.signals[4].write_function, 0);  // not given

  const std::string key = "devices/d/signals[0]/write_function: ";
  EXPECT_EQ(parseError(oneSignal("table: holding_register, address: 1, type: uint32, writable: "
                                 "true, write_function: 6")),
            key +
                "6 (write single register) cannot write the 2 registers of uint32; use 16 "
                "(write multiple registers)");
  EXPECT_EQ(parseError(oneSignal("table: holding_register, address: 1, writable: true, "
                                 "write_function: 5")),
            key +
                "5 is not a holding register write (6 = write single register, 16 = write "
                "multiple registers)");
  EXPECT_EQ(parseError(oneSignal("table: coil, address: 1, writable: true, write_function: 16")),
            key + "16 is not a coil write (5 = write single coil, 15 = write multiple coils)");
  EXPECT_EQ(parseError(oneSignal("table: holding_register, address: 1, writable: true, "
                                 "write_function: 0")),
            key + "0 is not a write function (6 or 16)");
  EXPECT_EQ(parseError(oneSignal("table: coil, address: 1, write_function: 15")),
            key + "only for writable signals (writable: true)");
  EXPECT_EQ(parseError(oneSignal("table: coil, address: 1, writable: true, write_function: x"))
                .rfind(key, 0),
            0u);
}

TEST(SignalYaml, TemplatesRelativeAndByFindAndTheirErrors) {
  char dir_template[] = "/tmp/test_signal_XXXXXX";
  const char* made = mkdtemp(dir_template);
  ASSERT_NE(made, nullptr) << "mkdtemp: " << std::strerror(errno);
  const std::string dir = made;
  mkdir((dir + "/pkg").c_str(), 0755);
  std::ofstream(dir + "/pkg/package.xml") << "<package><name>pkg</name></package>\n";
  std::ofstream(dir + "/pkg/t.yaml")
      << "signals: [{name: v, table: input_register, address: 0, type: float32}]\n";
  std::ofstream(dir + "/bad.yaml") << "signals: [{name: v, table: input_register}]\n";
  // Relative to the configuration's directory, and with extra signals beside the template's.
  const auto m = parseSignalMap(
      YAML::Load("{template: pkg/t.yaml, signals: [{name: w, table: coil, address: 0}]}"),
      "devices/d/", dir);
  ASSERT_EQ(m.signals.size(), 2u);
  EXPECT_EQ(m.signals[0].name, "v");
  EXPECT_EQ(m.signals[1].name, "w");
  const char* saved = std::getenv("ROS_PACKAGE_PATH");
  const std::string saved_path = saved ? saved : "";
  setenv("ROS_PACKAGE_PATH", ("/nonexistent:" + dir).c_str(), 1);
  EXPECT_EQ(
      parseSignalMap(YAML::Load("template: $(find pkg)/t.yaml"), "devices/d/", "").signals.size(),
      1u);
  EXPECT_EQ(parseError("template: $(find nopkg)/t.yaml"),
            "devices/d/template: $(find nopkg): no package of that name on ROS_PACKAGE_PATH");
  EXPECT_EQ(parseError("template: t.yaml").rfind("devices/d/template: 't.yaml' is relative", 0),
            0u);
  EXPECT_EQ(parseError("template: missing.yaml", dir).rfind("devices/d/template: cannot load", 0),
            0u);
  // A template's own errors name the file and the key inside it.
  EXPECT_EQ(parseError("template: bad.yaml", dir),
            "devices/d/template " + dir + "/bad.yaml: signals[0]/address: missing");
  if (saved)
    setenv("ROS_PACKAGE_PATH", saved_path.c_str(), 1);
  else
    unsetenv("ROS_PACKAGE_PATH");
  std::filesystem::remove_all(dir);
}

TEST(SignalYaml, TheShippedTemplatesParse) {
  for (const char* file : {"xy_md02.yaml", "sdm120.yaml"}) {
    const auto m = parseSignalMap(YAML::Load(std::string("template: templates/") + file),
                                  "devices/d/", std::string(REPO_DIR) + "/config");
    EXPECT_GE(m.signals.size(), 2u) << file;
  }
}
