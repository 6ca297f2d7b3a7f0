// LD58A08: 8 digital outputs (coils 0-7, mirrored in holding register 0x0080), each also a PWM
// channel. Channels 0-5 are slow (period / on-time in 0.1 s, pulse count at 0x00n2), channels
// 6-7 fast (frequency Hz, duty %, output time in 0.1 s at 0x00n2). Addresses 1-248 (248 goes
// through the link's own framing, as libmodbus 3.1.6 cannot address it). Manual: seeds/000.
#pragma once

#include <array>

#include "modbus_rtu_driver/core/config/device_types/ld58a08.h"
#include "modbus_rtu_driver/devices/device.h"
#include "modbus_rtu_driver/devices/self_timed_outputs.h"

namespace modbus_rtu_driver {

struct PwmSettings {
  uint8_t channel = 0;
  // Channels 0-5.
  double period = 0.0;   // s, 0.1-6553.5
  double on_time = 0.0;  // s, 0-6553.4 and <= period
  uint16_t pulses = 0;   // 1-65534; 0 = continuous (written as 0xFFFF)
  // Channels 6-7.
  double frequency = 0.0;   // Hz, 1-20000
  double duty_cycle = 0.0;  // %, 0-100
  double duration = 0.0;    // s, 0.1-6553.4; 0 = continuous (written as 0xFFFF)
};

// What the device reports for a channel (registers 0x00n0-0x00n2 decoded). The enable register
// (0x00n2) is split into explicit fields: 0 = stopped, 0xFFFF = continuous, else what is left.
struct PwmState {
  uint8_t channel = 0;
  bool high_speed = false;
  bool running = false;     // enable register not 0: the PWM drives the output
  bool continuous = false;  // enable register 0xFFFF: runs until stopped
  double period = 0.0, on_time = 0.0;
  uint16_t remaining_pulses = 0;  // channels 0-5: pulses left of a burst (1-65534), else 0
  double frequency = 0.0, duty_cycle = 0.0;
  double remaining_time = 0.0;  // s, channels 6-7: output time left of a timed run, else 0
  uint16_t enable = 0;          // the raw enable register
};

// The special function registers a user may change (manual, 0x00FA-0x00FF). Address, baud and
// parity change how the board answers: the address at once, baud and parity after a power cycle.
enum class Ld58a08Setting : uint16_t {
  kPowerDownSave = 0x00FA,  // 0 off, 1 on
  kReturnDelay = 0x00FC,    // x 40 ms, 0-25
  kAddress = 0x00FD,        // 1-248
  kBaud = 0x00FE,           // code 0-7 (1200-115200); 8 and above would be a factory reset
  kParity = 0x00FF,         // 0 none, 1 even, 2 odd
};

struct Ld58a08Settings {
  uint16_t power_down_save = 0;  // 0x00FA
  uint16_t return_delay = 0;     // 0x00FC, x40 ms, 0-25
  uint16_t address = 1;          // 0x00FD, 1-248
  uint16_t baud_code = 3;        // 0x00FE, 0-7
  uint16_t parity = 0;           // 0x00FF, 0 none 1 even 2 odd
};

class Ld58a08 : public Device, public SelfTimedOutputs {
 public:
  static constexpr size_t kChannels = kLd58a08Type.outputs;
  static constexpr uint16_t kOutputMaskRegister = 0x0080;
  static constexpr uint16_t kPowerDownSaveRegister = 0x00FA;
  static constexpr uint16_t kFactoryResetRegister = 0x00FB;
  static constexpr uint16_t kReturnDelayRegister = 0x00FC;
  static constexpr uint16_t kAddressRegister = 0x00FD;
  static constexpr uint16_t kBaudRegister = 0x00FE;
  static constexpr uint16_t kParityRegister = 0x00FF;
  static uint16_t pwmRegister(uint8_t channel) { return static_cast<uint16_t>(channel * 0x10); }

  explicit Ld58a08(DeviceConfig config) : Device(kLd58a08Type, std::move(config)) {}
  // Its PWM runs are outputs it times by itself.
  SelfTimedOutputs* selfTimed() override { return this; }

  // Polls the outputs (FC01) and the PWM registers of one channel (all on the first poll).
  Result poll(Transport& link) override;
  // Empty when valid, else a message naming the field and its range.
  static std::string validatePwm(const PwmSettings& settings);
  // One FC16 write of the channel's three registers.
  Result setPwm(Transport& link, const PwmSettings& settings);
  // That write (never retried: a second copy would run a burst twice).
  Request pwmWrite(const PwmSettings& settings) const;
  // What a PWM run does to its output: the device drives it until the burst or the timed run
  // ends, then it is off; a continuous run has no end (and can be started again: its write).
  TimedIntent pwmIntent(const PwmSettings& settings) const;
  // A continuous run's write again (a restore): as setPwm sends it, confirmed the same way.
  Result startAgain(Transport& link, const Request& write) override;
  // A client's write of a channel's enable register (0x00n2) that starts a run.
  std::vector<TimedIntent> timedWrittenBy(const Request& request) const override;
  // A client's write of 0 to a channel's enable register: that channel's run stopped.
  std::vector<uint8_t> timedStoppedBy(const Request& request) const override;
  // A client's confirmed write: the PWM snapshot takes the registers it set.
  void noteCarriedWrite(const Request& request) override;
  Result refreshSelfTimed(Transport& link) override { return readPwm(link); }
  bool coilWriteKeepsRun() const override { return true; }
  void noteRunKept(uint8_t channel) override {
    if (channel < kChannels) pwm_[channel].running = true;
  }
  // Writes 0 to the channel's enable register (0x00n2); a lost reply is confirmed by reading
  // the channel back.
  Result stopPwm(Transport& link, uint8_t channel);
  Result readPwm(Transport& link);  // fills pwm()
  const std::array<PwmState, kChannels>& pwm() const { return pwm_; }
  bool outputSelfTimed(size_t channel) const override {
    return !pwm_known_ || (channel < kChannels && pwm_[channel].running);
  }
  bool pwmKnown() const { return pwm_known_; }
  bool selfTimedRead() const override { return pwm_known_; }
  bool selfTimedReadByLastPoll(size_t channel) const override {
    return channel < kChannels && pwm_read_by_poll_[channel];
  }
  void readSelfTimedFirst(const std::vector<uint8_t>& channels) override {
    for (uint8_t ch : channels)
      if (ch < kChannels) pwm_unsure_[ch] = true;
  }

  Result readSettings(Transport& link, Ld58a08Settings* out);
  // Empty when `value` is in the setting's range, else a message naming it and the range.
  static std::string validateSetting(Ld58a08Setting setting, uint16_t value);
  Result readSetting(Transport& link, Ld58a08Setting setting, uint16_t* value);
  // FC06 to the setting's register, refused unsent outside its range. A new address is not
  // taken by this object (it keeps asking at the configured one).
  Result writeSetting(Transport& link, Ld58a08Setting setting, uint16_t value);
  Result setReturnDelay(Transport& link, uint16_t units_of_40ms) {
    return writeSetting(link, Ld58a08Setting::kReturnDelay, units_of_40ms);
  }
  // FC06 0 to 0x00FB: address 1 at once, 9600 8N1 after a power cycle, PWM cleared. The manual
  // sends it through 0xFF (every LD58A08 on the bus takes it).
  Result factoryReset(Transport& link);

 protected:
  // The outputs drive a channel only while its PWM is off (manual, 0x0080): reads the requested
  // channels' PWM registers, stops (FC06 0 to 0x00n2, confirmed) those that run, then writes the
  // outputs (FC05 / FC15). The message then says "PWM on channel N stopped first".
  Result writeOutputs(Transport& link, const std::vector<uint8_t>& channels,
                      const std::vector<bool>& states, std::vector<uint8_t>* changed = nullptr,
                      const std::vector<bool>& timed_may_run = {}) override;

 private:
  // A continuous run the device confirmed (set_pwm's, or a client's write the node carried):
  // the snapshot says it runs until a read says otherwise.
  void noteContinuousRun(uint8_t channel);
  // Sends a PWM write of one channel's three registers; a lost answer is read back.
  Result writePwm(Transport& link, const Request& write);
  Result readPwmChannel(Transport& link, uint8_t channel, PwmState* out);
  Result confirmPwm(Transport& link, Result failed, uint8_t channel,
                    const std::vector<uint16_t>& written);

  std::array<PwmState, kChannels> pwm_{};
  std::array<bool, kChannels> pwm_read_by_poll_{};  // the channels the newest poll read
  uint8_t poll_cursor_ = 0;
  // Channels whose PWM write or stop went unconfirmed (its answer and the read back lost, or the
  // read back not sent to a device that gave no reply), and those the fail-safe waits to read
  // (readSelfTimedFirst): the next poll reads them first, so the fail-safe learns what the
  // channel does at the next poll, not up to 8 polls later.
  std::array<bool, kChannels> pwm_unsure_{};
  bool pwm_known_ = false;
};

}  // namespace modbus_rtu_driver
