#include "modbus_rtu_driver/devices/yespeed_pdu.h"

#include <cmath>
#include <cstdarg>
#include <cstdio>

#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/devices/registry.h"

namespace modbus_rtu_driver {

// `type: yespeed_pdu` in the bus YAML builds this class (devices/registry.h).
[[maybe_unused]] const bool kYespeedPduRegistered =
    deviceClasses().add(kYespeedPduType, makeDevice<YespeedPdu>);

namespace {

std::string fmt(const char* pattern, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* pattern, ...) {
  char buf[256];
  va_list args;
  va_start(args, pattern);
  // The analyzer loses va_start across the attribute-declared prototype: a false report.
  std::vsnprintf(buf, sizeof buf, pattern, args);  // NOLINT(clang-analyzer-valist.Uninitialized)
  va_end(args);
  return buf;
}

// "250.0 V" / "16.00 A" for a register value of limit `which`.
std::string regText(size_t which, long reg) {
  return which == 2 ? fmt("%.2f A", reg / 100.0) : fmt("%.1f V", reg / 10.0);
}

// The rule of one limit on its own, on the register value; empty when it holds.
std::string ownRule(size_t which, long reg, const std::string& name) {
  const std::string what =
      name + ": " + regText(which, reg) + " (register " + std::to_string(reg) + ")";
  if (which == 0 && !(reg > 1800)) return what + " must be above 180.0 V (1800)";
  if (which == 1 && !(reg < 2800)) return what + " must be below 280.0 V (2800)";
  if (which == 2 && !(reg > 500 && reg < 2000))
    return what + " must be between 5.00 A and 20.00 A (500-2000, exclusive)";
  return {};
}

}  // namespace

Result YespeedPdu::poll(Transport& link) {
  reading_fresh_ = false;  // a poll that stops at the relays read has no telemetry either
  Result relays = link.execute(Request::readCoils(address(), 0, kRelays));
  if (mayHaveActed(relays)) return relays;  // silent or garbled: do not spend more of the line
  if (relays.ok()) outputs_.assign(relays.values.begin(), relays.values.end());
  Result telemetry = readTelemetry(link);
  if (relays.ok() && telemetry.ok() && !limits_known_) readLimits(link);
  return relays.ok() ? telemetry : relays;
}

Result YespeedPdu::readTelemetry(Transport& link) {
  reading_fresh_ = false;
  Result r = link.execute(Request::readInputRegisters(address(), 0, 5));
  if (!r.ok()) return r;
  reading_.temperature = static_cast<int16_t>(r.values[0]) / 10.0;
  reading_.humidity = r.values[1] / 10.0;
  reading_.voltage = r.values[2] / 10.0;
  reading_.current = r.values[3] / 100.0;
  reading_.power = r.values[4];
  reading_fresh_ = true;
  return r;
}

Result YespeedPdu::readLimits(Transport& link) {
  Result r = link.execute(Request::readHoldingRegisters(address(), 0, 3));
  if (!r.ok()) return r;
  limit_registers_ = {r.values[0], r.values[1], r.values[2]};
  limits_ = limitValues(limit_registers_);
  limits_known_ = true;
  return r;
}

std::string YespeedPdu::limitToRegister(size_t which, double value, uint16_t* reg,
                                        const std::string& name_in) {
  const std::string name = name_in.empty() ? kLimitNames[which] : name_in;
  const double step = kLimitSteps[which];
  const char* unit = kLimitUnits[which];
  const double max = 65535 * step;
  // Convert first: the rules apply to the integer that goes on the wire.
  const double units = value / step;
  const bool finite = std::isfinite(units);
  const double nearest = finite ? std::round(units) : 0;
  // float32 (a ROS message) carries about 7 digits: allow that much noise, no more.
  const double noise = 1e-3 + 1e-7 * std::fabs(units);
  if (!finite || nearest < 0 || nearest > 65535 || std::fabs(units - nearest) > noise)
    return fmt("%s: %s %s is outside 0-%g %s in steps of %g %s", name.c_str(),
               numberText(value).c_str(), unit, max, unit, step, unit);
  const long r = static_cast<long>(nearest);
  std::string broken = ownRule(which, r, name);
  if (!broken.empty()) return broken;
  *reg = static_cast<uint16_t>(r);
  return {};
}

std::string YespeedPdu::checkLimitRegisters(const PduLimitRegisters& regs) {
  for (size_t i = 0; i < 3; ++i) {
    std::string broken = ownRule(i, regs[i], kLimitNames[i]);
    if (!broken.empty()) return broken;
  }
  if (!(regs[0] > regs[1]))
    return "over_voltage: " + regText(0, regs[0]) + " must be above under_voltage (" +
           regText(1, regs[1]) + ")";
  return {};
}

std::string YespeedPdu::validateLimits(const PduLimitValues& l, PduLimitRegisters* out) {
  const double values[3] = {l.over_voltage, l.under_voltage, l.over_current};
  PduLimitRegisters regs{};
  for (size_t i = 0; i < 3; ++i) {
    std::string problem = limitToRegister(i, values[i], &regs[i]);
    if (!problem.empty()) return problem;
  }
  std::string problem = checkLimitRegisters(regs);
  if (problem.empty() && out) *out = regs;
  return problem;
}

PduLimitRegisters YespeedPdu::mergeLimits(const PduLimitRegisters& current,
                                          const PduLimitChange& change) {
  PduLimitRegisters merged = current;
  for (size_t i = 0; i < 3; ++i) merged[i] = change[i].value_or(current[i]);
  return merged;
}

PduLimitValues YespeedPdu::limitValues(const PduLimitRegisters& regs) {
  PduLimitValues l;
  l.over_voltage = regs[0] / 10.0;
  l.under_voltage = regs[1] / 10.0;
  l.over_current = regs[2] / 100.0;
  return l;
}

std::string YespeedPdu::limitsText(const PduLimitRegisters& regs) {
  return regText(0, regs[0]) + " / " + regText(1, regs[1]) + " / " + regText(2, regs[2]);
}

Result YespeedPdu::setLimits(Transport& link, const PduLimitValues& l) {
  PduLimitRegisters regs{};
  const std::string problem = validateLimits(l, &regs);
  if (!problem.empty()) return Result::failure(ErrorKind::kInvalidArgument, problem);
  return writeLimitRegisters(link, regs);
}

Result YespeedPdu::writeLimitRegisters(Transport& link, const PduLimitRegisters& regs) {
  const std::string problem = checkLimitRegisters(regs);
  if (!problem.empty()) return Result::failure(ErrorKind::kInvalidArgument, problem);
  Result w =
      link.execute(Request::writeMultipleRegisters(address(), 0, {regs[0], regs[1], regs[2]}));
  if (!w.ok()) return w;
  // Read back so the latched limits show what the device holds, not what was asked.
  Result r = readLimits(link);
  if (!r.ok()) {
    r.message += " (reading the limits back after writing them)";
    return r;
  }
  if (limit_registers_ != regs)
    return Result::failure(ErrorKind::kMalformed, "the device accepted " + limitsText(regs) +
                                                      " but holds " + limitsText(limit_registers_));
  return w;
}

Result YespeedPdu::changeLimits(Transport& link, const PduLimitChange& change) {
  PduLimitRegisters current{};
  const bool partial = !change[0] || !change[1] || !change[2];
  if (partial) {
    Result r = readLimits(link);  // the limits not given stay as the device holds them
    if (!r.ok()) {
      r.message += " (reading the current limits; nothing was written)";
      return r;
    }
    current = limit_registers_;
  }
  const PduLimitRegisters merged = mergeLimits(current, change);
  const std::string problem = checkLimitRegisters(merged);
  if (!problem.empty())
    return Result::failure(ErrorKind::kInvalidArgument,
                           partial ? problem + " (merged with the limits the device holds: " +
                                         limitsText(merged) + "; nothing was written)"
                                   : problem);
  return writeLimitRegisters(link, merged);
}

}  // namespace modbus_rtu_driver
