// Simulated Yespeed PDU (manual seeds/002): relays (coils 0-7), telemetry in input registers 0-4
// that moves plausibly over time, protection limits in holding registers 0-2 with the manual's
// rules (a write breaking them is refused with exception 03).
#pragma once

#include <array>
#include <map>

#include "modbus_rtu_driver/sim/sim_device.h"

namespace modbus_rtu_driver {

class SimYespeedPdu : public SimDevice {
 public:
  SimYespeedPdu(uint8_t address, SimLineSettings line);
  const char* type() const override { return "yespeed_pdu"; }
  void powerCycle() override;
  void saveState(YAML::Node& node) const override;
  void loadState(const YAML::Node& node) override;
  uint8_t read(Table table, uint16_t address, SimClock::time_point now, uint16_t* value) override;
  uint8_t write(Table table, uint16_t address, const std::vector<uint16_t>& values,
                SimClock::time_point now) override;
  // `set ireg` pins a telemetry register until the next power cycle.
  uint8_t setDirect(Table table, uint16_t address, uint16_t value,
                    SimClock::time_point now) override;

  // The manual's rules (register units: 0.1 V, 0.1 V, 0.01 A).
  static bool limitsValid(uint16_t over_voltage, uint16_t under_voltage, uint16_t over_current);

 private:
  uint16_t telemetry(uint16_t index, SimClock::time_point now) const;

  uint8_t relays_ = 0;
  std::array<uint16_t, 3> limits_{2500, 2000, 1600};
  std::map<uint16_t, uint16_t> pinned_;
  SimClock::time_point born_ = SimClock::now();
};

}  // namespace modbus_rtu_driver
