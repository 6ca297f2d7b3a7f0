#include "modbus_rtu_driver/core/config/signal.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

#include "modbus_rtu_driver/core/config/number_text.h"

namespace modbus_rtu_driver {

const char* typeName(SignalType t) {
  return nameIn(kSignalTypeNames, t).data();  // the names are literals: terminated
}

uint16_t wordsOf(SignalType t) {
  switch (t) {
    case SignalType::kUint32:
    case SignalType::kInt32:
    case SignalType::kFloat32:
      return 2;
    case SignalType::kUint64:
    case SignalType::kInt64:
      return 4;
    default:
      return 1;
  }
}

double rawMin(SignalType t) {
  switch (t) {
    case SignalType::kInt16:
      return -32768.0;
    case SignalType::kInt32:
      return -2147483648.0;
    case SignalType::kInt64:
      return -9223372036854775808.0;
    case SignalType::kFloat32:
      return -std::numeric_limits<float>::max();
    default:
      return 0.0;
  }
}

double rawMax(SignalType t) {
  switch (t) {
    case SignalType::kBool:
      return 1.0;
    case SignalType::kUint16:
      return 65535.0;
    case SignalType::kInt16:
      return 32767.0;
    case SignalType::kUint32:
      return 4294967295.0;
    case SignalType::kInt32:
      return 2147483647.0;
    case SignalType::kFloat32:
      return std::numeric_limits<float>::max();
    case SignalType::kUint64:
      return 18446744073709551615.0;
    case SignalType::kInt64:
      return 9223372036854775807.0;
  }
  return 0.0;
}

int SignalConfig::writeFunction() const {
  if (write_function != 0) return write_function;
  if (table == Table::kCoil) return 5;
  return words() == 1 ? 6 : 16;
}

std::string writeFunctionProblem(const SignalConfig& s) {
  const int fc = s.writeFunction();
  const std::string given = std::to_string(fc);
  if (s.table == Table::kCoil) {
    if (fc == 5 || fc == 15) return {};
    return given + " is not a coil write (5 = write single coil, 15 = write multiple coils)";
  }
  if (s.table != Table::kHoldingRegister)
    return std::string("a ") + tableName(s.table) + " cannot be written";
  if (fc == 16 || (fc == 6 && s.words() == 1)) return {};
  if (fc == 6)
    return "6 (write single register) cannot write the " + std::to_string(s.words()) +
           " registers of " + typeName(s.type) + "; use 16 (write multiple registers)";
  return given +
         " is not a holding register write (6 = write single register, 16 = write multiple "
         "registers)";
}

namespace {

// "nan", never "-nan" (a `.nan` in YAML or a service field comes back as the user wrote it).
std::string number(double v) {
  return numberText(v);
}

// The value a raw number becomes on the device (float32 keeps only its 24 bits).
double writtenValue(const SignalConfig& s, double raw) {
  if (s.type == SignalType::kFloat32) raw = static_cast<float>(raw);
  return s.toValue(raw);
}

// min <= written <= max, up to the arithmetic's own error (0.1 * 3 is 0.30000000000000004):
// far below one step of any scale, and below float32's precision for float32.
bool withinLimits(const SignalConfig& s, double written) {
  const double relative = s.type == SignalType::kFloat32 ? 1e-6 : 1e-9;
  auto slack = [&](double bound) { return relative * std::max(1.0, std::abs(bound)); };
  return !(s.min && written < *s.min - slack(*s.min)) &&
         !(s.max && written > *s.max + slack(*s.max));
}

// The value's words with the most significant first, from the registers in address order.
uint64_t joinWords(uint16_t n, WordOrder order, const uint16_t* words) {
  uint64_t v = 0;
  for (uint16_t i = 0; i < n; ++i) v = (v << 16) | words[order == WordOrder::kBig ? i : n - 1 - i];
  return v;
}

std::vector<uint16_t> splitWords(uint16_t n, WordOrder order, uint64_t v) {
  std::vector<uint16_t> words(n);
  for (uint16_t i = 0; i < n; ++i) {  // i = 0: the least significant word
    const auto w = static_cast<uint16_t>(v >> (16 * i));
    words[order == WordOrder::kBig ? n - 1 - i : i] = w;
  }
  return words;
}

}  // namespace

std::string writeValueProblem(const SignalConfig& s, double value, std::vector<uint16_t>* words) {
  if (s.type == SignalType::kBool) {
    if (value != 0.0 && value != 1.0) return number(value) + " is not 0 or 1";
    *words = {static_cast<uint16_t>(value)};
    return {};
  }
  if (!std::isfinite(value)) return number(value) + " is not a finite number";
  const std::string unit = s.unit.empty() ? "" : " " + s.unit;
  const std::string range =
      (s.min ? number(*s.min) : "-inf") + " to " + (s.max ? number(*s.max) : "inf") + unit;
  if ((s.min && value < *s.min) || (s.max && value > *s.max))
    return number(value) + unit + " is outside " + range;
  double raw = s.toRaw(value);
  if (s.type != SignalType::kFloat32) raw = std::round(raw);
  if (raw < rawMin(s.type) || raw > rawMax(s.type))
    return number(value) + unit + " is raw " + number(raw) + ", outside what " + typeName(s.type) +
           " holds (" + number(rawMin(s.type)) + " to " + number(rawMax(s.type)) + ")";
  // min / max bound what the device gets, not what was asked: a register holds steps of
  // `scale`, so 95 with scale 10 would be written as raw 10, which is 100.
  const double written = writtenValue(s, raw);
  if (!withinLimits(s, written))
    return number(value) + unit + " would be written as " + number(written) + unit + " (raw " +
           number(raw) + "), outside " + range;
  *words = encodeRaw(s.type, s.word_order, raw);
  return {};
}

double decodeRaw(SignalType type, WordOrder order, const uint16_t* words) {
  const uint64_t bits = joinWords(wordsOf(type), order, words);
  switch (type) {
    case SignalType::kBool:
      return bits ? 1.0 : 0.0;
    case SignalType::kInt16:
      return static_cast<int16_t>(bits);
    case SignalType::kInt32:
      return static_cast<int32_t>(bits);
    case SignalType::kInt64:
      return static_cast<double>(static_cast<int64_t>(bits));
    case SignalType::kFloat32: {
      const auto u = static_cast<uint32_t>(bits);
      float f;
      std::memcpy(&f, &u, sizeof f);
      return f;
    }
    default:
      return static_cast<double>(bits);
  }
}

std::vector<uint16_t> encodeRaw(SignalType type, WordOrder order, double raw) {
  uint64_t bits = 0;
  if (type == SignalType::kFloat32) {
    const auto f = static_cast<float>(raw);
    uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    bits = u;
  } else if (type == SignalType::kBool) {
    bits = raw != 0.0 ? 1 : 0;
  } else if (type == SignalType::kUint64) {
    // 2^64 as a double is the type's max rounded up: the top value.
    bits = raw >= 18446744073709551615.0 ? ~uint64_t{0} : static_cast<uint64_t>(std::round(raw));
  } else if (type == SignalType::kInt64 && raw >= 9223372036854775807.0) {
    bits = static_cast<uint64_t>(std::numeric_limits<int64_t>::max());
  } else {
    bits = static_cast<uint64_t>(std::llround(raw));  // two's complement for the signed ones
  }
  return splitWords(wordsOf(type), order, bits);
}

}  // namespace modbus_rtu_driver
