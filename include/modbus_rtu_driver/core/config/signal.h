// One value of a device described in YAML (the `generic` device type): where it lives (table,
// address), how its registers make a number (type, word order) and how that number becomes an
// engineering value (scale, offset). Shared by the bus node's generic device and the simulator,
// so both read the same description the same way. ROS-free.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/modbus/types.h"

namespace modbus_rtu_driver {

enum class SignalType { kBool, kUint16, kInt16, kUint32, kInt32, kFloat32, kUint64, kInt64 };
// big: the most significant word at the lowest address (Modbus's usual order); little: the
// least significant word first. Bytes inside a register are always big-endian (the protocol's).
enum class WordOrder { kBig, kLittle };
inline constexpr NameTable<SignalType, 8> kSignalTypeNames{{{SignalType::kBool, "bool"},
                                                            {SignalType::kUint16, "uint16"},
                                                            {SignalType::kInt16, "int16"},
                                                            {SignalType::kUint32, "uint32"},
                                                            {SignalType::kInt32, "int32"},
                                                            {SignalType::kFloat32, "float32"},
                                                            {SignalType::kUint64, "uint64"},
                                                            {SignalType::kInt64, "int64"}}};
inline constexpr NameTable<WordOrder, 2> kWordOrderNames{
    {{WordOrder::kBig, "big"}, {WordOrder::kLittle, "little"}}};

const char* typeName(SignalType type);
// Registers (or bits) one value of `type` takes.
uint16_t wordsOf(SignalType type);
// The raw values a type can hold (uint64/int64 as doubles: exact up to 2^53).
double rawMin(SignalType type);
double rawMax(SignalType type);

struct SignalConfig {
  std::string name;  // a ROS name: topic D/<name>
  Table table = Table::kHoldingRegister;
  uint16_t address = 0;
  SignalType type = SignalType::kUint16;
  WordOrder word_order = WordOrder::kBig;
  double scale = 1.0;  // value = raw * scale + offset
  double offset = 0.0;
  std::string unit;
  bool writable = false;            // coils and holding registers only
  std::optional<double> min, max;   // allowed written values, in engineering units
  std::optional<double> poll_rate;  // Hz; none = the device's
  // Fail-safe: what the node writes on shutdown, heartbeat loss and on_start: safe
  // (engineering units; bits 0 or 1); none = left as it is. Writable signals only.
  std::optional<double> safe_value;
  // Function code a write uses: 5 or 15 (coils), 6 or 16 (holding registers); 0 = the default.
  int write_function = 0;

  uint16_t words() const { return wordsOf(type); }
  // write_function, or the default: 5 for a coil, 6 for one register, 16 for more.
  int writeFunction() const;
  // Engineering value <-> raw number.
  double toValue(double raw) const { return raw * scale + offset; }
  double toRaw(double value) const { return (value - offset) / scale; }
};

// Why `s.write_function` cannot write `s` (a message naming the value and what is allowed), or
// empty when it can. Shared by the YAML check and the device, so a bad one never reaches the bus.
std::string writeFunctionProblem(const SignalConfig& s);

// Why `value` cannot be written to `s` (without the signal's name: "95 l/h would be written as
// 100 l/h (raw 10), outside 12 to 95 l/h"), or empty when it can; then `words` holds the
// registers (or the bit) it becomes. Checks min/max on the value asked and on the value the
// rounded raw number stands for, then the type's range. Shared by the device's writes and the
// YAML check of safe_value, so a value the node would refuse is never configured.
std::string writeValueProblem(const SignalConfig& s, double value, std::vector<uint16_t>* words);

// The raw number in `words` (wordsOf(type) registers in address order; bits as 0/1).
double decodeRaw(SignalType type, WordOrder order, const uint16_t* words);
// The registers (in address order) that hold `raw`; `raw` must be in the type's range (integer
// types round to the nearest whole number).
std::vector<uint16_t> encodeRaw(SignalType type, WordOrder order, double raw);

// A generic device's description: its signals and how far apart two may be and still be read
// in one request.
struct SignalMapConfig {
  std::vector<SignalConfig> signals;
  int max_gap = 8;  // registers (bits for coils / discrete inputs) read and thrown away, 0-123
};

// The keys a generic device takes beside the common ones, and a signal's keys.
extern const std::vector<std::string> kSignalMapKeys;  // signals, template, max_gap
extern const std::vector<std::string> kSignalKeys;

// Reads `signals`, `template` and `max_gap` of a device map `n` (keys named `where` + key).
// A template path may start with $(find PKG) (searched on ROS_PACKAGE_PATH) or be relative to
// `base_dir` (the directory of the file the configuration came from; empty: unknown, so a
// relative path is an error). Throws config::ConfigError naming the key.
SignalMapConfig parseSignalMap(const YAML::Node& n, const std::string& where,
                               const std::string& base_dir);
// Where a template path points: $(find PKG) resolved, relative paths on `base_dir`. Throws.
std::string resolveTemplatePath(const std::string& path, const std::string& key,
                                const std::string& base_dir);

}  // namespace modbus_rtu_driver
