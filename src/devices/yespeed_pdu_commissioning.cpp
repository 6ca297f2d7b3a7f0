// The Yespeed PDU in modbus_rtu_commission (devices/commissioning.h): told apart by its five
// input registers, `info` shows its readings and limits. It has no address or line settings
// the manual documents (seeds/002); its limits have commands of their own (get/set-limits).
#include <sstream>

#include "modbus_rtu_driver/devices/commissioning.h"
#include "modbus_rtu_driver/devices/yespeed_pdu.h"

namespace modbus_rtu_driver {

namespace {

class YespeedPduCommissioning : public Commissioning {
 public:
  // After the LD58A08's probe (more specific), before the LC board's (less specific).
  int probeOrder() const override { return 20; }

  Probe probe(Transport& bus, uint8_t address) const override {
    Probe p;
    const Result r = bus.execute(Request::readInputRegisters(address, 0, 5));
    p.unclear = !answered(r);
    if (r.ok()) p.kind = Probe::kYes;
    return p;
  }

  Result report(Transport& bus, uint8_t address, InfoReport* out) const override {
    DeviceConfig d;
    d.name = d.type = kYespeedPduType.name;
    d.address = address;
    YespeedPdu pdu(d);
    Result r = pdu.readTelemetry(bus);
    if (r.ok()) r = pdu.readLimits(bus);
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

  bool has(BoardFeature) const override { return false; }
  std::string title() const override { return "the PDU"; }
};

const YespeedPduCommissioning kCommissioning;

}  // namespace

[[maybe_unused]] const bool kYespeedPduCommissioningRegistered =
    commissioningClasses().add(kYespeedPduType, &kCommissioning);

}  // namespace modbus_rtu_driver
