// Simulated LD58A08 (manual seeds/000): coils 0-7 with the 0x0080 mirror, PWM per channel
// (0x00n0-0x00n2) that really runs over time, and the special registers 0x00FA-0x00FF.
#pragma once

#include <array>

#include "modbus_rtu_driver/sim/sim_device.h"

namespace modbus_rtu_driver {

class SimLd58a08 : public SimDevice {
 public:
  SimLd58a08(uint8_t address, SimLineSettings line);
  const char* type() const override { return "ld58a08"; }
  // "Only one module on the bus": it also answers its special registers (0x00FA-0x00FF) at
  // 0xFF, as the manual shows. Reading it as answering everything at 0xFF would make it
  // collide with an LC relay board at its factory address 255 on every poll.
  bool answersTo(uint8_t slave, const Request* request) const override {
    return slave == address_ || (slave == 0xFF && request && !isBitFunction(request->function) &&
                                 request->address >= 0x00FA && request->address <= 0x00FF);
  }
  double replyDelay() const override { return return_delay_ * 0.040; }
  void tick(SimClock::time_point now) override;
  void powerCycle() override;
  void saveState(YAML::Node& node) const override;
  void loadState(const YAML::Node& node) override;
  uint8_t read(Table table, uint16_t address, SimClock::time_point now, uint16_t* value) override;
  uint8_t write(Table table, uint16_t address, const std::vector<uint16_t>& values,
                SimClock::time_point now) override;

 private:
  struct Channel {
    uint16_t reg[3] = {0, 0, 0};  // period/frequency, on-time/duty, pulses/output time
    SimClock::time_point started{};
    uint16_t started_with = 0;  // enable register when the run started
  };
  void start(uint8_t ch, SimClock::time_point now);
  void factoryReset();
  uint8_t writeHolding(uint16_t address, uint16_t value, SimClock::time_point now);

  uint8_t outputs_ = 0;  // bit n = channel n
  std::array<Channel, 8> pwm_{};
  uint16_t save_ = 0, return_delay_ = 0;
  uint16_t baud_code_ = 3, parity_code_ = 0;  // pending until a power cycle
};

}  // namespace modbus_rtu_driver
