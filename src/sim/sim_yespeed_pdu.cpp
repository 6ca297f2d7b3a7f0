#include "modbus_rtu_driver/sim/sim_yespeed_pdu.h"

#include <yaml-cpp/yaml.h>

#include <bitset>
#include <cmath>

namespace modbus_rtu_driver {

SimYespeedPdu::SimYespeedPdu(uint8_t address, SimLineSettings line) : SimDevice(address, line) {}

bool SimYespeedPdu::limitsValid(uint16_t ov, uint16_t uv, uint16_t oc) {
  return ov > uv && ov > 1800 && uv < 2800 && oc > 500 && oc < 2000;
}

// Slow drifts plus a little ripple; current follows the number of relays switched on.
uint16_t SimYespeedPdu::telemetry(uint16_t index, SimClock::time_point now) const {
  auto pin = pinned_.find(index);
  if (pin != pinned_.end()) return pin->second;
  const double t = std::chrono::duration<double>(now - born_).count();
  const double voltage = 220.0 + 2.0 * std::sin(t / 7.0) + 0.3 * std::sin(t * 3.1);
  const double current = 0.25 + 0.9 * std::bitset<8>(relays_).count() + 0.05 * std::sin(t * 1.7);
  switch (index) {
    case 0:
      return static_cast<uint16_t>(
          static_cast<int16_t>(std::lround((22.0 + 0.8 * std::sin(t / 30.0)) * 10)));
    case 1:
      return static_cast<uint16_t>(std::lround((55.0 + 3.0 * std::sin(t / 45.0)) * 10));
    case 2:
      return static_cast<uint16_t>(std::lround(voltage * 10));
    case 3:
      return static_cast<uint16_t>(std::lround(current * 100));
    default:
      return static_cast<uint16_t>(std::lround(voltage * current * 0.95));  // W, PF 0.95
  }
}

uint8_t SimYespeedPdu::read(Table table, uint16_t a, SimClock::time_point now, uint16_t* v) {
  switch (table) {
    case Table::kCoil:
      if (a > 7) return kIllegalDataAddress;
      *v = (relays_ >> a) & 1;
      return 0;
    case Table::kInputRegister:
      if (a > 4) return kIllegalDataAddress;
      *v = telemetry(a, now);
      return 0;
    case Table::kHolding:
      if (a > 2) return kIllegalDataAddress;
      *v = limits_[a];
      return 0;
    default:
      return kIllegalFunction;  // the manual opens no FC02 table
  }
}

uint8_t SimYespeedPdu::write(Table table, uint16_t a, const std::vector<uint16_t>& values,
                             SimClock::time_point) {
  if (table == Table::kCoil) {
    if (a + values.size() > 8) return kIllegalDataAddress;
    for (size_t i = 0; i < values.size(); ++i) {
      const uint8_t bit = static_cast<uint8_t>(1u << (a + i));
      relays_ = values[i] ? (relays_ | bit) : (relays_ & static_cast<uint8_t>(~bit));
    }
    return 0;
  }
  if (table != Table::kHolding) return kIllegalFunction;
  if (a + values.size() > 3) return kIllegalDataAddress;
  auto next = limits_;
  for (size_t i = 0; i < values.size(); ++i) next[a + i] = values[i];
  if (!limitsValid(next[0], next[1], next[2])) return kIllegalDataValue;  // checked as a whole
  limits_ = next;
  return 0;
}

uint8_t SimYespeedPdu::setDirect(Table table, uint16_t a, uint16_t v, SimClock::time_point now) {
  if (table != Table::kInputRegister) return SimDevice::setDirect(table, a, v, now);
  if (a > 4) return kIllegalDataAddress;
  pinned_[a] = v;
  return 0;
}

void SimYespeedPdu::powerCycle() {
  relays_ = 0;
  pinned_.clear();
}

void SimYespeedPdu::saveState(YAML::Node& n) const {
  n["address"] = static_cast<int>(address_);
  for (uint16_t l : limits_) n["limits"].push_back(l);
}

void SimYespeedPdu::loadState(const YAML::Node& n) {
  address_ = static_cast<uint8_t>(n["address"].as<int>(address_));
  if (n["limits"] && n["limits"].size() == 3)
    for (size_t i = 0; i < 3; ++i) limits_[i] = n["limits"][i].as<uint16_t>();
}

}  // namespace modbus_rtu_driver
