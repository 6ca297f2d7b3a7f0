// Simulated LC Technology 8-relay board (manual seeds/001): factory address 255, relays
// (coils 0-7), optocoupler inputs (discrete inputs 0-7, 1 = input pulled low), flash-close /
// flash-open at 0x0003 + 5*n that revert by themselves, baud code at 0x03E9 (write) / 0x03E8
// (read), and address read / set through slave address 0.
#pragma once

#include <array>

#include "modbus_rtu_driver/sim/sim_device.h"

namespace modbus_rtu_driver {

class SimLcRelay8 : public SimDevice {
 public:
  SimLcRelay8(uint8_t address, SimLineSettings line);
  const char* type() const override { return "lc_relay8"; }
  // Address commands at slave 0 (the board answers them: "single device on the bus").
  std::optional<Bytes> handleAtZero(const Request& request);
  void tick(SimClock::time_point now) override;
  void powerCycle() override;
  void saveState(YAML::Node& node) const override;
  void loadState(const YAML::Node& node) override;
  uint8_t read(Table table, uint16_t address, SimClock::time_point now, uint16_t* value) override;
  uint8_t write(Table table, uint16_t address, const std::vector<uint16_t>& values,
                SimClock::time_point now) override;
  uint8_t setDirect(Table table, uint16_t address, uint16_t value,
                    SimClock::time_point now) override;

 private:
  struct Flash {
    uint16_t mode = 0, delay = 0;  // last written
    bool active = false;
    SimClock::time_point ends{};
  };
  uint8_t relays_ = 0, inputs_ = 0;
  std::array<Flash, 8> flash_{};
  uint16_t baud_code_ = 3;  // pending until a power cycle
};

}  // namespace modbus_rtu_driver
