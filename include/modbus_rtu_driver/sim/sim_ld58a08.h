// Simulated LD58A08 (manual seeds/000): coils 0-7 with the 0x0080 mirror, PWM per channel
// (0x00n0-0x00n2) that really runs over time, and the special registers 0x00FA-0x00FF.
//
// Decisions where the manual is silent:
// - A new address (0x00FD) answers from the next request on; the reply to the change still comes
//   from the old address (the manual's reply echoes the request's slave byte).
// - Baud (0x00FE) and parity (0x00FF) are stored at once and read back as stored; the line
//   uses them after a power cycle. Parity > 2 is stored and becomes 0 at power-on (manual).
// - Factory reset (a write to 0x00FB, or baud code > 7): address 1 at once; baud 9600, parity
//   none from the next power-on; return delay 0, power-down save off, every PWM channel stopped
//   and cleared (its output off). Plain outputs stay as they are.
// - Addresses 1-248 (0x01-0xF8, the manual's range for 0x00FD); 0 and 249-65535 get exception 03.
// - While a channel's PWM runs, its output bit follows the waveform, whatever a coil write (FC05,
//   FC15) or a 0x0080 write says; the write is acknowledged (manual, 0x0080: the outputs apply
//   only with the enable register at 0).
//   A fast channel (6, 7) reads as on while it runs with a duty cycle above 0.
// - PWM values outside the manual's ranges are refused with exception 03: period 0, on-time
//   65535 or longer than the period, frequency outside 1-20000 Hz, duty cycle over 100 %, and
//   starting a channel whose period / frequency is 0.
#pragma once

#include <array>

#include "modbus_rtu_driver/core/config/device_types/ld58a08.h"
#include "modbus_rtu_driver/sim/sim_device.h"

namespace modbus_rtu_driver {

class SimLd58a08 : public SimDevice {
 public:
  SimLd58a08(uint8_t address, SimLineSettings line);
  const char* type() const override { return kLd58a08Type.name; }
  // "Only one module on the bus": it also answers its special registers (0x00FA-0x00FF) at
  // 0xFF, as the manual shows, whoever else is at 255: beside an LC board at its factory
  // address 255 both answer those frames and the replies collide on the line (simulator.h).
  // The node refuses that configuration. Whether a real board answers every request at 0xFF
  // is not known; the simulator takes only what the manual shows.
  bool answersTo(uint8_t slave, const Request* request) const override {
    return slave == address_ || (slave == 0xFF && request && !isBitFunction(request->function) &&
                                 request->address >= 0x00FA && request->address <= 0x00FF);
  }
  double replyDelay() const override { return return_delay_ * 0.040; }
  bool startsSomething(const Request& request) const override;  // a PWM run (enable != 0)
  void tick(SimClock::time_point now) override;
  void powerCycle(SimClock::time_point now) override;
  void saveState(YAML::Node& node) const override;
  void loadState(const YAML::Node& node, SimClock::time_point now) override;
  uint8_t read(Table table, uint16_t address, SimClock::time_point now, uint16_t* value) override;
  uint8_t write(Table table, uint16_t address, const std::vector<uint16_t>& values,
                SimClock::time_point now) override;

 private:
  using Registers = std::array<uint16_t, 3>;  // period|frequency, on-time|duty, pulses|time
  struct Channel {
    Registers reg{};
    Registers stored{};  // as last written over the bus: what power-down save keeps
    SimClock::time_point anchor{};
    uint16_t anchored_with = 0;  // the enable register at the anchor
  };
  void anchor(uint8_t ch, SimClock::time_point now);
  void stopChannel(uint8_t ch);
  void setOutput(uint8_t ch, bool on);
  void restartSaved(SimClock::time_point now);
  uint8_t checkHolding(uint16_t address, const std::vector<uint16_t>& values) const;
  void writeHolding(uint16_t address, uint16_t value, SimClock::time_point now);
  void factoryReset();

  uint8_t outputs_ = 0;  // bit n = channel n
  std::array<Channel, 8> pwm_{};
  uint16_t save_ = 0, return_delay_ = 0;
  uint16_t baud_code_ = 3, parity_code_ = 0;  // stored; the line takes them at power-on
};

}  // namespace modbus_rtu_driver
