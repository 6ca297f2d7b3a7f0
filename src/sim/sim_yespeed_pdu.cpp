#include "modbus_rtu_driver/sim/sim_yespeed_pdu.h"

#include <yaml-cpp/yaml.h>

#include <cmath>

#include "modbus_rtu_driver/sim/simulator.h"

namespace modbus_rtu_driver {

// `type: yespeed_pdu` in the simulator's file builds this class (sim/simulator.h).
[[maybe_unused]] const bool kSimYespeedPduRegistered =
    simDeviceClasses().add(kYespeedPduType, makeSimDeviceOf<SimYespeedPdu>);

namespace {

constexpr double kPowerFactor = 0.98;
constexpr auto kMeasureEvery = std::chrono::milliseconds(500);
// What each outlet's load draws, in A: different appliances, about 0.9 A each on average.
constexpr double kLoad[8] = {0.85, 1.20, 0.60, 0.95, 1.10, 0.75, 0.90, 1.05};
constexpr double kOwnCurrent = 0.05;  // the PDU's own electronics

uint16_t toRegister(double v, double scale) {
  return static_cast<uint16_t>(static_cast<int16_t>(std::lround(v * scale)));
}

}  // namespace

SimYespeedPdu::SimYespeedPdu(uint8_t address, SimLineSettings line)
    : SimYespeedPdu(address, line, SimClock::now()) {}

SimYespeedPdu::SimYespeedPdu(uint8_t address, SimLineSettings line, SimClock::time_point born)
    : SimDevice(address, line), born_(born), noise_(address) {
  measure(born_);
}

bool SimYespeedPdu::limitsValid(uint16_t ov, uint16_t uv, uint16_t oc) {
  return ov > uv && ov > 1800 && uv < 2800 && oc > 500 && oc < 2000;
}

void SimYespeedPdu::measure(SimClock::time_point now) {
  const double t = std::chrono::duration<double>(now - born_).count();
  std::uniform_real_distribution<double> jitter(-1.0, 1.0);
  double load = kOwnCurrent;  // at 220 V
  for (int i = 0; i < 8; ++i)
    if (relays_ & (1u << i)) load += kLoad[i] * (1.0 + 0.03 * std::sin(t / 11.0 + i));
  const double voltage = 220.0 + 2.0 * std::sin(t / 70.0) + 0.2 * jitter(noise_) - 0.4 * load;
  const double current = load * voltage / 220.0 * (1.0 + 0.005 * jitter(noise_));  // resistive
  const double temperature = 22.0 + 0.8 * std::sin(t / 300.0) + 0.15 * load + 0.05 * jitter(noise_);
  const double humidity = 55.0 + 3.0 * std::sin(t / 450.0) + 0.1 * jitter(noise_);
  measured_[0] = toRegister(temperature, 10.0);
  measured_[1] = toRegister(humidity, 10.0);
  measured_[2] = toRegister(voltage, 10.0);
  measured_[3] = toRegister(current, 100.0);
  measured_relays_ = relays_;
  next_measure_ = now + kMeasureEvery;
}

uint16_t SimYespeedPdu::value(uint16_t index) const {
  if (pinned_[index]) return pins_[index];
  if (index < 4) return measured_[index];
  // Power from the registers a reader sees, so the three agree.
  return toRegister(value(2) / 10.0 * value(3) / 100.0 * kPowerFactor, 1.0);
}

void SimYespeedPdu::tick(SimClock::time_point now) {
  if (now >= next_measure_ || relays_ != measured_relays_) measure(now);
}

uint8_t SimYespeedPdu::read(Table table, uint16_t a, SimClock::time_point now, uint16_t* v) {
  tick(now);
  switch (table) {
    case Table::kCoil:
      if (a > 7) return kIllegalDataAddress;
      *v = (relays_ >> a) & 1;
      return 0;
    case Table::kInputRegister:
      if (a > 4) return kIllegalDataAddress;
      *v = value(a);
      return 0;
    case Table::kHoldingRegister:
      if (a > 2) return kIllegalDataAddress;
      *v = limits_[a];
      return 0;
    default:
      return kIllegalFunction;  // the manual opens no FC02 table
  }
}

uint8_t SimYespeedPdu::write(Table table, uint16_t a, const std::vector<uint16_t>& values,
                             SimClock::time_point now) {
  if (table == Table::kCoil) {
    if (a + values.size() > 8) return kIllegalDataAddress;
    for (size_t i = 0; i < values.size(); ++i) {
      const uint8_t bit = static_cast<uint8_t>(1u << (a + i));
      relays_ = values[i] ? (relays_ | bit) : (relays_ & static_cast<uint8_t>(~bit));
    }
    tick(now);  // the current follows the outlets at once
    return 0;
  }
  if (table != Table::kHoldingRegister) return kIllegalFunction;
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
  pinned_[a] = true;
  pins_[a] = v;
  return 0;
}

void SimYespeedPdu::powerCycle(SimClock::time_point now) {
  relays_ = 0;
  pinned_ = {};
  measure(now);
}

void SimYespeedPdu::saveState(YAML::Node& n) const {
  n["address"] = static_cast<int>(address_);
  for (uint16_t l : limits_) n["limits"].push_back(l);
}

void SimYespeedPdu::loadState(const YAML::Node& n, SimClock::time_point) {
  const int address = n["address"].as<int>(address_);
  if (address >= 1 && address <= 247) address_ = static_cast<uint8_t>(address);
  if (n["limits"] && n["limits"].IsSequence() && n["limits"].size() == 3) {
    const std::array<uint16_t, 3> l{n["limits"][0].as<uint16_t>(0), n["limits"][1].as<uint16_t>(0),
                                    n["limits"][2].as<uint16_t>(0)};
    if (limitsValid(l[0], l[1], l[2])) limits_ = l;
  }
}

}  // namespace modbus_rtu_driver
