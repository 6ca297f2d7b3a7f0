// Yespeed PDU: relay coils 0-7, input registers 0-4 (temperature signed x0.1 C, humidity
// x0.1 %, voltage x0.1 V, current x0.01 A, power W), holding registers 0-2 (over-voltage x0.1 V,
// under-voltage x0.1 V, over-current x0.01 A). Manual: seeds/002.
#pragma once

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

class YespeedPdu : public Device {
 public:
  static constexpr size_t kRelays = 8;

  explicit YespeedPdu(DeviceConfig config) : Device(std::move(config)) {}
  const char* type() const override { return "yespeed_pdu"; }
  size_t outputCount() const override { return kRelays; }

  // FC01 relays, then one FC04 for all five readings. Limits are read once (and after writes).
  Result poll(Transport& bus) override;
  Result setOutputs(Transport& bus, const std::vector<uint8_t>& channels,
                    const std::vector<bool>& states) override;

  Result readTelemetry(Transport& bus);  // fills reading()
  Result readLimits(Transport& bus);     // fills limits()
  // The manual's rules: over > under, over > 180 V, under < 280 V, 5 A < current < 20 A,
  // each in the register's resolution and range. Empty when valid.
  static std::string validateLimits(const PduLimitValues& limits);
  // One FC16 write of registers 0-2, then a read back.
  Result setLimits(Transport& bus, const PduLimitValues& limits);

  const PduReading& reading() const { return reading_; }
  bool readingFresh() const { return reading_fresh_; }  // the last poll's read succeeded
  const PduLimitValues& limits() const { return limits_; }
  bool limitsKnown() const { return limits_known_; }

 private:
  PduReading reading_;
  bool reading_fresh_ = false;
  PduLimitValues limits_;
  bool limits_known_ = false;
};

}  // namespace modbus_rtu_driver
