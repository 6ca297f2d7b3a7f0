// Simulated Yespeed PDU (manual seeds/002): relays (coils 0-7), telemetry in input registers 0-4
// (temperature 0.1 C signed, humidity 0.1 %, voltage 0.1 V, current 0.01 A, power W) that moves
// plausibly over time, protection limits in holding registers 0-2 with the manual's rules (a
// write breaking them is refused with exception 03; an FC16 is checked as a whole).
//
// The telemetry is measured every 0.5 s and at once when a relay switches: slow drifts plus a
// little noise; the current is what the switched-on outlets draw (resistive loads: it follows
// the voltage); the power is voltage x current x 0.98 (power factor) of the register values.
// `set DEV input_register` pins a register until the next power cycle; a pinned voltage or current
// still enters the power.
#pragma once

#include <array>
#include <random>

#include "modbus_rtu_driver/core/config/device_types/yespeed_pdu.h"
#include "modbus_rtu_driver/sim/sim_device.h"

namespace modbus_rtu_driver {

class SimYespeedPdu : public SimDevice {
 public:
  SimYespeedPdu(uint8_t address, SimLineSettings line);
  // `born`: where its telemetry's slow waves start (the default: now). A simulation on a manual
  // clock gives its own start, so that the same run reads the same values.
  SimYespeedPdu(uint8_t address, SimLineSettings line, SimClock::time_point born);
  const char* type() const override { return kYespeedPduType.name; }
  void tick(SimClock::time_point now) override;
  void powerCycle(SimClock::time_point now) override;
  void saveState(YAML::Node& node) const override;
  void loadState(const YAML::Node& node, SimClock::time_point now) override;
  uint8_t read(Table table, uint16_t address, SimClock::time_point now, uint16_t* value) override;
  uint8_t write(Table table, uint16_t address, const std::vector<uint16_t>& values,
                SimClock::time_point now) override;
  uint8_t setDirect(Table table, uint16_t address, uint16_t value,
                    SimClock::time_point now) override;

  // The manual's rules (register units: 0.1 V, 0.1 V, 0.01 A).
  static bool limitsValid(uint16_t over_voltage, uint16_t under_voltage, uint16_t over_current);

 private:
  void measure(SimClock::time_point now);
  uint16_t value(uint16_t index) const;  // pinned or measured

  uint8_t relays_ = 0;
  std::array<uint16_t, 3> limits_{2500, 2000, 1600};
  std::array<uint16_t, 5> measured_{};
  std::array<bool, 5> pinned_{};
  std::array<uint16_t, 5> pins_{};
  SimClock::time_point born_, next_measure_{};
  uint8_t measured_relays_ = 0;
  std::mt19937 noise_;
};

}  // namespace modbus_rtu_driver
