// Yespeed PDU: relay coils 0-7, input registers 0-4 (temperature signed x0.1 C, humidity
// x0.1 %, voltage x0.1 V, current x0.01 A, power W), holding registers 0-2 (over-voltage x0.1 V,
// under-voltage x0.1 V, over-current x0.01 A). Manual: seeds/002.
#pragma once

#include <array>
#include <optional>

#include "modbus_rtu_driver/core/config/device_types/yespeed_pdu.h"
#include "modbus_rtu_driver/devices/device.h"

namespace modbus_rtu_driver {

struct PduReading {
  double temperature = 0;  // degC
  double humidity = 0;     // %RH
  double voltage = 0;      // V
  double current = 0;      // A
  double power = 0;        // W
};

struct PduLimitValues {
  double over_voltage = 0;   // V
  double under_voltage = 0;  // V
  double over_current = 0;   // A
};

// The three limits as the registers hold them: 0.1 V, 0.1 V, 0.01 A (holding registers 0-2).
using PduLimitRegisters = std::array<uint16_t, 3>;
// A change of some of them; an empty field keeps what the device holds.
using PduLimitChange = std::array<std::optional<uint16_t>, 3>;

class YespeedPdu : public Device {
 public:
  static constexpr size_t kRelays = kYespeedPduType.outputs;

  explicit YespeedPdu(DeviceConfig config) : Device(kYespeedPduType, std::move(config)) {}

  // FC01 relays, then one FC04 for all five readings. Limits are read once (and after writes).
  Result poll(Transport& link) override;
  Result readTelemetry(Transport& link);  // fills reading()
  Result readLimits(Transport& link);     // fills limits()
  static constexpr const char* kLimitNames[3] = {"over_voltage", "under_voltage", "over_current"};
  static constexpr const char* kLimitUnits[3] = {"V", "V", "A"};
  static constexpr double kLimitSteps[3] = {0.1, 0.1, 0.01};

  // Converts limit `which` (0 over-voltage, 1 under-voltage, 2 over-current; V or A) to the
  // register value that would be written (the nearest whole step: 0.1 V, 0.01 A; float32 noise
  // allowed), then checks that value's own rule from the manual on the integer. `name` is what
  // the message calls the field (default kLimitNames). Empty when fine.
  static std::string limitToRegister(size_t which, double value, uint16_t* reg,
                                     const std::string& name = "");
  // The manual's rules on the register values: over > under, over > 1800 (180 V), under < 2800
  // (280 V), 500 < current < 2000 (5-20 A), all strict. Empty when valid.
  static std::string checkLimitRegisters(const PduLimitRegisters& regs);
  // Both of the above, for all three values. Empty when valid; `regs` may be null.
  static std::string validateLimits(const PduLimitValues& limits,
                                    PduLimitRegisters* regs = nullptr);
  // The fields of `change` over `current` (what the device holds).
  static PduLimitRegisters mergeLimits(const PduLimitRegisters& current,
                                       const PduLimitChange& change);
  static PduLimitValues limitValues(const PduLimitRegisters& regs);
  // "250.0 V / 200.0 V / 16.00 A"
  static std::string limitsText(const PduLimitRegisters& regs);

  // One FC16 write of registers 0-2 (checked first: nothing is sent when a rule is broken),
  // then a read back, which must show what was written.
  Result setLimits(Transport& link, const PduLimitValues& limits);
  Result writeLimitRegisters(Transport& link, const PduLimitRegisters& regs);
  // Some of the limits: reads the others from the device first, checks the rules on the merged
  // values, then writes all three as above.
  Result changeLimits(Transport& link, const PduLimitChange& change);

  const PduReading& reading() const { return reading_; }
  bool readingFresh() const { return reading_fresh_; }  // the last poll's read succeeded
  const PduLimitValues& limits() const { return limits_; }
  const PduLimitRegisters& limitRegisters() const { return limit_registers_; }
  bool limitsKnown() const { return limits_known_; }

 private:
  PduReading reading_;
  bool reading_fresh_ = false;
  PduLimitValues limits_;
  PduLimitRegisters limit_registers_{};
  bool limits_known_ = false;
};

}  // namespace modbus_rtu_driver
