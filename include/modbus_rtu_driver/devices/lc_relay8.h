// LC Technology 8-relay board with 8 optocoupler inputs: coils 0-7 (relay #1-#8), discrete
// inputs 0-7 (1 = input pulled low), flash-close / flash-open at 0x0003 + 5*n (FC16: mode,
// delay in 0.1 s), baud code write 0x03E9 / read 0x03E8, address read/set through slave 0.
// Factory address 255. Manual: seeds/001.
#pragma once

#include "modbus_rtu_driver/core/config/device_types/lc_relay8.h"
#include "modbus_rtu_driver/devices/device.h"

namespace modbus_rtu_driver {

class LcRelay8 : public Device {
 public:
  static constexpr size_t kChannels = kLcRelay8Type.outputs;
  static constexpr uint16_t kFlashClose = 0x0004;
  static constexpr uint16_t kFlashOpen = 0x0002;
  static constexpr uint16_t kBaudWriteRegister = 0x03E9;
  static constexpr uint16_t kBaudReadRegister = 0x03E8;
  static uint16_t flashRegister(uint8_t channel) { return static_cast<uint16_t>(3 + 5 * channel); }

  explicit LcRelay8(DeviceConfig config) : Device(kLcRelay8Type, std::move(config)) {}

  // FC01 relays then FC02 inputs.
  Result poll(Transport& link) override;
  // Empty when valid: channel 0-7, duration 0.1-6553.5 s. The duration is converted to the
  // delay register's 0.1 s steps first (the nearest step, float noise allowed); the range is
  // checked on that integer (0x0001-0xFFFF), which goes to `tenths` when not null.
  static std::string pulseTenths(uint8_t channel, double duration, uint16_t* tenths);
  static std::string validatePulse(uint8_t channel, double duration);
  // state true = flash-close (on for duration, then off); false = flash-open.
  Result pulse(Transport& link, uint8_t channel, bool state, double duration);
  // A client's FC16 over a relay's mode and delay registers: that relay's flash.
  std::vector<TimedIntent> timedWrittenBy(const Request& request) const override;

  Result readBaudCode(Transport& link, uint16_t* code);
  Result writeBaudCode(Transport& link, uint16_t code);  // 2, 3, 4 = 4800, 9600, 19200

  // "Single device on the bus" operations at address 0 (any LC board answers them).
  static Result readAddressAtZero(Transport& link);                  // values[0] = address
  static Result setAddressAtZero(Transport& link, uint8_t address);  // 1-255
};

}  // namespace modbus_rtu_driver
