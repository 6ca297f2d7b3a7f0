// Simulated LC Technology 8-relay board (manual seeds/001): factory address 255, relays
// (coils 0-7), optocoupler inputs (discrete inputs 0-7, 1 = input pulled low), flash-close /
// flash-open at 0x0003 + 5*n that revert by themselves, baud code at 0x03E9 (write) / 0x03E8
// (read), and address read / set through slave address 0.
//
// Decisions where the manual is silent:
// - 0x03E8 reads the stored baud code (what a write to 0x03E9 set), like the LD58A08's 0x00FE;
//   the line uses it after a power cycle.
// - A coil write to a relay cancels its running flash. The flash registers read back the last
//   mode and delay written (FC03); other holding registers are exception 02.
// - A power cycle opens every relay and ends every flash; the inputs are wiring and stay.
#pragma once

#include <array>

#include "modbus_rtu_driver/core/config/device_types/lc_relay8.h"
#include "modbus_rtu_driver/sim/sim_device.h"

namespace modbus_rtu_driver {

class SimLcRelay8 : public SimDevice {
 public:
  SimLcRelay8(uint8_t address, SimLineSettings line);
  const char* type() const override { return kLcRelay8Type.name; }
  // The board's commands at slave 0: read the address (FC03 register 0, count 1) and set it
  // (FC16 register 0, one value). Only an LC board handles these; it answers them. Other
  // broadcasts it applies silently, as every device does.
  static bool isAddressCommand(const Request& request);
  std::optional<Bytes> handleBroadcast(const Request& request, SimClock::time_point now) override;
  void tick(SimClock::time_point now) override;
  void powerCycle(SimClock::time_point now) override;
  void saveState(YAML::Node& node) const override;
  void loadState(const YAML::Node& node, SimClock::time_point now) override;
  bool startsSomething(const Request& request) const override;  // a timed flash
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
  void setRelay(uint8_t ch, bool on);

  uint8_t relays_ = 0, inputs_ = 0;
  std::array<Flash, 8> flash_{};
  uint16_t baud_code_ = 3;          // stored; the line takes it at power-on
  bool baud_code_written_ = false;  // since the simulator started (powerCycle)
};

}  // namespace modbus_rtu_driver
