#pragma once
// Numbers in messages as people write them: "1 s", "0.05 s", "2.5 Hz", "nan" (never
// "1.000000" from std::to_string, nor "-nan" from printf).
#include <cmath>
#include <cstdio>
#include <string>

namespace modbus_rtu_driver {

// Up to 6 significant digits, no trailing zeros; nan / inf / -inf spelled out.
inline std::string numberText(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v == 0.0 ? 0.0 : v);  // no "-0"
  return buf;
}

// A measured duration, rounded as a person reads it: "0.4 s", "3.5 s", "12 s".
inline std::string secondsText(double s) {
  if (!std::isfinite(s)) return numberText(s) + " s";
  return numberText(s < 10.0 ? std::round(s * 10.0) / 10.0 : std::round(s)) + " s";
}

}  // namespace modbus_rtu_driver
