// The LD58A08 in modbus_rtu_commission (devices/commissioning.h): its special function
// registers 0x00FA-0x00FF, the address read and set at its own address or through 0xFF, which
// every LD58A08 answers as "whoever you are" (manual, seeds/000).
#include "modbus_rtu_driver/devices/commissioning.h"
#include "modbus_rtu_driver/devices/ld58a08.h"

namespace modbus_rtu_driver {

namespace {

DeviceConfig at(int address) {
  return boardConfig(kLd58a08Type, address == kBlind ? kLd58a08Type.also_answers : address);
}

Ld58a08Setting registerOf(BoardFeature which) {
  switch (which) {
    case BoardFeature::kBaud:
      return Ld58a08Setting::kBaud;
    case BoardFeature::kParity:
      return Ld58a08Setting::kParity;
    case BoardFeature::kReturnDelay:
      return Ld58a08Setting::kReturnDelay;
    case BoardFeature::kPowerDownSave:
      return Ld58a08Setting::kPowerDownSave;
    default:
      return Ld58a08Setting::kAddress;
  }
}

class Ld58a08Commissioning : public Commissioning {
 public:
  // First: its probe (its address register holds the address asked) is the most specific, and
  // an LD58A08 answering 0xFF must be known before others are asked there.
  int probeOrder() const override { return 10; }

  Probe probe(Transport& link, uint8_t address) const override {
    return probeByRead(link, Request::readHoldingRegisters(address, Ld58a08::kAddressRegister, 1),
                       [address](const std::vector<uint16_t>& values, Probe* p) {
                         if (values[0] == address) {
                           p->kind = Probe::kYes;
                         } else if (address == kLd58a08Type.also_answers) {
                           // It answers 0xFF as "whoever you are": it is at its own address, not at
                           // 255.
                           p->kind = Probe::kElsewhere;
                           p->note =
                               "an LD58A08 answered for its address " + std::to_string(values[0]);
                         }
                       });
  }

  Result report(Transport& link, uint8_t address, InfoReport* out) const override {
    Ld58a08 board(at(address));
    Ld58a08Settings st;
    Result r = board.readSettings(link, &st);
    if (!r.ok()) return r;
    out->human = "\n  stored baud rate: " + baudCodeText(st.baud_code) +
                 "\n  stored parity: " + parityCodeText(st.parity) +
                 "\n  return delay: " + std::to_string(st.return_delay * returnDelayStepMs()) +
                 " ms\n  power-down save: " + (st.power_down_save ? "on" : "off");
    out->fields = {{"baud_code", int{st.baud_code}},
                   {"baud", baudOfCode(st.baud_code)},
                   {"parity_code", int{st.parity}},
                   {"return_delay_ms", st.return_delay * returnDelayStepMs()},
                   {"save", int{st.power_down_save}}};
    return r;
  }

  bool has(BoardFeature feature) const override { return feature != BoardFeature::kLimits; }
  std::string title() const override { return "the LD58A08"; }

  std::string addressPath() const override { return "through 0xFF"; }
  Result readAddress(Transport& link, int address, uint16_t* value) const override {
    return Ld58a08(at(address)).readSetting(link, Ld58a08Setting::kAddress, value);
  }
  Result writeAddress(Transport& link, int address, uint16_t value) const override {
    return Ld58a08(at(address)).writeSetting(link, Ld58a08Setting::kAddress, value);
  }
  Result answersAt(Transport& link, int address) const override {
    uint16_t there = 0;
    Result r = readAddress(link, address, &there);
    if (r.ok() && there != address)
      return Result::failure(ErrorKind::kMalformed,
                             "it reports address " + std::to_string(there) + " there");
    return r;
  }
  std::string addressPathWarning() const override {
    return "Every LD58A08 on the bus takes it: only one may be connected.";
  }
  std::string afterAddressChange() const override {
    return "It answers only at the new address from then on.";
  }
  // An LC board at its factory address 255 answers 0xFF too, and refuses this register.
  std::string addressReadHint(const Result& failed, int address) const override {
    if (failed.error != ErrorKind::kException || failed.exception_code != kIllegalDataAddress)
      return "";
    if (address == kBlind)
      return "; another board type may have answered (e.g. an LC relay board at its factory "
             "address 255: try --type lc_relay8)";
    const std::string a = std::to_string(address);
    return "; another board type may be at " + a + " (info --address " + a + " names it)";
  }

  std::pair<int, int> baudCodes() const override { return {0, 7}; }  // 8 and up: factory reset
  int returnDelayStepMs() const override { return 40; }
  int returnDelayMaxUnits() const override { return 25; }

  Result readSetting(Transport& link, int address, BoardFeature which,
                     uint16_t* value) const override {
    return Ld58a08(at(address)).readSetting(link, registerOf(which), value);
  }
  Result writeSetting(Transport& link, int address, BoardFeature which,
                      uint16_t value) const override {
    return Ld58a08(at(address)).writeSetting(link, registerOf(which), value);
  }

  std::string factoryResetAlsoText() const override {
    return ", no return delay, PWM settings cleared";
  }
  std::string factoryResetPathWarning() const override { return " (every LD58A08 on the link)"; }
  // FF 06 00 FB 00 00 ED E5 through 0xFF, as the manual prints it.
  Result factoryReset(Transport& link, int address) const override {
    return Ld58a08(at(address)).factoryReset(link);
  }
};

const Ld58a08Commissioning kCommissioning;

}  // namespace

[[maybe_unused]] const bool kLd58a08CommissioningRegistered =
    commissioningClasses().add(kLd58a08Type, &kCommissioning);

}  // namespace modbus_rtu_driver
