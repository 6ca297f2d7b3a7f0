// The LC Technology relay board in modbus_rtu_commission (devices/commissioning.h): its baud
// code (write 0x03E9, read 0x03E8), and its address, which it has no register for at its own
// address: read and set through address 0 only, with the board alone on the bus (manual,
// seeds/001).
#include "modbus_rtu_driver/devices/commissioning.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"

namespace modbus_rtu_driver {

namespace {

LcRelay8 boardAt(int address) {
  return LcRelay8(boardConfig(kLcRelay8Type, address));
}

class LcRelay8Commissioning : public Commissioning {
 public:
  // After the LD58A08's and the PDU's probes: a baud code register that reads 2-4 is the
  // least specific sign.
  int probeOrder() const override { return 30; }

  Probe probe(Transport& link, uint8_t address) const override {
    const auto [lo, hi] = baudCodes();
    return probeByRead(link, Request::readHoldingRegisters(address, LcRelay8::kBaudReadRegister, 1),
                       [lo = lo, hi = hi](const std::vector<uint16_t>& values, Probe* p) {
                         if (values[0] >= lo && values[0] <= hi) p->kind = Probe::kYes;
                       });
  }

  Result report(Transport& link, uint8_t address, InfoReport* out) const override {
    uint16_t code = 0;
    Result r = boardAt(address).readBaudCode(link, &code);
    if (!r.ok()) return r;
    out->human = "\n  baud rate: " + baudCodeText(code);
    out->fields = {{"baud_code", int{code}}, {"baud", baudOfCode(code)}};
    return r;
  }

  bool has(BoardFeature feature) const override {
    return feature == BoardFeature::kAddress || feature == BoardFeature::kBaud;
  }
  std::string title() const override { return "the LC relay board"; }

  std::string addressPath() const override { return "through address 0"; }
  bool addressReadableAt() const override { return false; }
  Result readAddress(Transport& link, int, uint16_t* value) const override {
    Result r = LcRelay8::readAddressAtZero(link);
    if (r.ok()) *value = r.values[0];
    return r;
  }
  Result writeAddress(Transport& link, int, uint16_t value) const override {
    return LcRelay8::setAddressAtZero(link, static_cast<uint8_t>(value));
  }
  // It has no address register there: reading its baud code is the harmless question.
  Result answersAt(Transport& link, int address) const override {
    uint16_t code = 0;
    return boardAt(address).readBaudCode(link, &code);
  }
  std::string addressPathWarning() const override {
    return "Every LC board on the bus takes it, and other devices see a write to their register "
           "0: only this board may be connected.";
  }

  std::pair<int, int> baudCodes() const override { return {2, 4}; }  // 4800, 9600, 19200
  std::string powerCycleAdvice() const override {
    return " (the manual advises about 30 s without power)";
  }
  Result readSetting(Transport& link, int address, BoardFeature which,
                     uint16_t* value) const override {
    if (which != BoardFeature::kBaud) return unsupported();
    return boardAt(address).readBaudCode(link, value);
  }
  Result writeSetting(Transport& link, int address, BoardFeature which,
                      uint16_t value) const override {
    if (which != BoardFeature::kBaud) return unsupported();
    return boardAt(address).writeBaudCode(link, value);
  }
};

const LcRelay8Commissioning kCommissioning;

}  // namespace

[[maybe_unused]] const bool kLcRelay8CommissioningRegistered =
    commissioningClasses().add(kLcRelay8Type, &kCommissioning);

}  // namespace modbus_rtu_driver
