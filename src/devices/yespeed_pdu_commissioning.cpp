// The Yespeed PDU in modbus_rtu_commission (devices/commissioning.h): told apart by its five
// input registers, `info` shows its readings and limits, and its limits (holding registers
// 0-2) are read and changed with the manual's rules (seeds/002). It has no address or line
// settings the manual documents.
#include <sstream>

#include "modbus_rtu_driver/devices/commissioning.h"
#include "modbus_rtu_driver/devices/yespeed_pdu.h"

namespace modbus_rtu_driver {

namespace {

YespeedPdu pduAt(int address) {
  return YespeedPdu(boardConfig(kYespeedPduType, address));
}

PduLimitRegisters asRegisters(const std::vector<uint16_t>& regs) {
  PduLimitRegisters out{};
  for (size_t i = 0; i < out.size() && i < regs.size(); ++i) out[i] = regs[i];
  return out;
}

class YespeedPduCommissioning : public Commissioning {
 public:
  // After the LD58A08's probe (more specific), before the LC board's (less specific).
  int probeOrder() const override { return 20; }

  Probe probe(Transport& link, uint8_t address) const override {
    return probeByRead(link, Request::readInputRegisters(address, 0, 5),
                       [](const std::vector<uint16_t>&, Probe* p) { p->kind = Probe::kYes; });
  }

  Result report(Transport& link, uint8_t address, InfoReport* out) const override {
    YespeedPdu pdu = pduAt(address);
    Result r = pdu.readTelemetry(link);
    if (r.ok()) r = pdu.readLimits(link);
    if (!r.ok()) return r;
    const PduReading& m = pdu.reading();
    const PduLimitValues& l = pdu.limits();
    std::ostringstream human;
    human << "\n  " << m.voltage << " V, " << m.current << " A, " << m.power << " W, "
          << m.temperature << " C, " << m.humidity << " %RH\n  limits: over-voltage "
          << l.over_voltage << " V, under-voltage " << l.under_voltage << " V, over-current "
          << l.over_current << " A";
    out->human = human.str();
    out->fields = {{"voltage", m.voltage},
                   {"current", m.current},
                   {"power", m.power},
                   {"temperature", m.temperature},
                   {"humidity", m.humidity}};
    return r;
  }

  bool has(BoardFeature feature) const override { return feature == BoardFeature::kLimits; }
  std::string title() const override { return "the PDU"; }

  std::vector<LimitSpec> limitList() const override {
    return {{YespeedPdu::kLimitNames[0], YespeedPdu::kLimitUnits[0], 1},
            {YespeedPdu::kLimitNames[1], YespeedPdu::kLimitUnits[1], 1},
            {YespeedPdu::kLimitNames[2], YespeedPdu::kLimitUnits[2], 2}};
  }
  std::string limitRules() const override {
    return "over-voltage above 180.0 V and above under-voltage, under-voltage below 280.0 V,\n"
           "      over-current above 5.00 A and below 20.00 A";
  }
  std::string limitToRegister(size_t which, double value, uint16_t* reg,
                              const std::string& option) const override {
    return YespeedPdu::limitToRegister(which, value, reg, option);
  }
  std::string checkLimits(const std::vector<uint16_t>& regs) const override {
    if (regs.size() != 3) return "limits: 3 values needed";
    return YespeedPdu::checkLimitRegisters(asRegisters(regs));
  }
  Result readLimits(Transport& link, int address, std::vector<uint16_t>* regs) const override {
    YespeedPdu pdu = pduAt(address);
    Result r = pdu.readLimits(link);
    if (r.ok()) regs->assign(pdu.limitRegisters().begin(), pdu.limitRegisters().end());
    return r;
  }
  Result writeLimits(Transport& link, int address,
                     const std::vector<uint16_t>& regs) const override {
    if (regs.size() != 3)
      return Result::failure(ErrorKind::kInvalidArgument, "limits: 3 values needed");
    return pduAt(address).writeLimitRegisters(link, asRegisters(regs));
  }
};

const YespeedPduCommissioning kCommissioning;

}  // namespace

[[maybe_unused]] const bool kYespeedPduCommissioningRegistered =
    commissioningClasses().add(kYespeedPduType, &kCommissioning);

}  // namespace modbus_rtu_driver
