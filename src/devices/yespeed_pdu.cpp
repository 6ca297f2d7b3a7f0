#include "modbus_rtu_driver/devices/yespeed_pdu.h"

#include <cmath>
#include <cstdio>

namespace modbus_rtu_driver {

namespace {

std::string fmt(const char* pattern, double a, double b = 0) {
  char buf[128];
  std::snprintf(buf, sizeof buf, pattern, a, b);
  return buf;
}

// `value` in units of `step`, if it is a whole number of them (float32 noise allowed).
bool toUnits(double value, double step, long* units) {
  const double u = value / step;
  *units = std::lround(u);
  return std::fabs(u - static_cast<double>(*units)) < 1e-3;
}

}  // namespace

Result YespeedPdu::poll(Transport& bus) {
  Result relays = bus.execute(Request::readCoils(address(), 0, kRelays));
  if (mayHaveActed(relays)) return relays;  // silent or garbled: do not spend more of the line
  if (relays.ok()) outputs_.assign(relays.values.begin(), relays.values.end());
  Result telemetry = readTelemetry(bus);
  if (relays.ok() && telemetry.ok() && !limits_known_) readLimits(bus);
  return relays.ok() ? telemetry : relays;
}

Result YespeedPdu::setOutputs(Transport& bus, const std::vector<uint8_t>& channels,
                              const std::vector<bool>& states) {
  return writeCoilOutputs(bus, channels, states);
}

Result YespeedPdu::readTelemetry(Transport& bus) {
  reading_fresh_ = false;
  Result r = bus.execute(Request::readInputRegisters(address(), 0, 5));
  if (!r.ok()) return r;
  reading_.temperature = static_cast<int16_t>(r.values[0]) / 10.0;
  reading_.humidity = r.values[1] / 10.0;
  reading_.voltage = r.values[2] / 10.0;
  reading_.current = r.values[3] / 100.0;
  reading_.power = r.values[4];
  reading_fresh_ = true;
  return r;
}

Result YespeedPdu::readLimits(Transport& bus) {
  Result r = bus.execute(Request::readHoldingRegisters(address(), 0, 3));
  if (!r.ok()) return r;
  limits_.over_voltage = r.values[0] / 10.0;
  limits_.under_voltage = r.values[1] / 10.0;
  limits_.over_current = r.values[2] / 100.0;
  limits_known_ = true;
  return r;
}

std::string YespeedPdu::validateLimits(const PduLimitValues& l) {
  long u = 0;
  if (!(l.over_voltage >= 0 && l.over_voltage <= 6553.5) || !toUnits(l.over_voltage, 0.1, &u))
    return fmt("over_voltage: %g V is outside 0-6553.5 V in steps of 0.1 V", l.over_voltage);
  if (!(l.under_voltage >= 0 && l.under_voltage <= 6553.5) || !toUnits(l.under_voltage, 0.1, &u))
    return fmt("under_voltage: %g V is outside 0-6553.5 V in steps of 0.1 V", l.under_voltage);
  if (!(l.over_current >= 0 && l.over_current <= 655.35) || !toUnits(l.over_current, 0.01, &u))
    return fmt("over_current: %g A is outside 0-655.35 A in steps of 0.01 A", l.over_current);
  if (!(l.over_voltage > 180.0))
    return fmt("over_voltage: %g V must be above 180 V", l.over_voltage);
  if (!(l.under_voltage < 280.0))
    return fmt("under_voltage: %g V must be below 280 V", l.under_voltage);
  if (!(l.over_voltage > l.under_voltage))
    return fmt("over_voltage: %g V must be above under_voltage (%g V)", l.over_voltage,
               l.under_voltage);
  if (!(l.over_current > 5.0 && l.over_current < 20.0))
    return fmt("over_current: %g A must be between 5 A and 20 A (exclusive)", l.over_current);
  return {};
}

Result YespeedPdu::setLimits(Transport& bus, const PduLimitValues& l) {
  const std::string problem = validateLimits(l);
  if (!problem.empty()) return Result::failure(ErrorKind::kInvalidArgument, problem);
  long ov = 0, uv = 0, oc = 0;
  toUnits(l.over_voltage, 0.1, &ov);
  toUnits(l.under_voltage, 0.1, &uv);
  toUnits(l.over_current, 0.01, &oc);
  Result w = bus.execute(Request::writeMultipleRegisters(
      address(), 0,
      {static_cast<uint16_t>(ov), static_cast<uint16_t>(uv), static_cast<uint16_t>(oc)}));
  if (!w.ok()) return w;
  // Read back so the latched limits show what the device holds, not what was asked.
  Result r = readLimits(bus);
  return r.ok() ? w : r;
}

}  // namespace modbus_rtu_driver
