#include "modbus_rtu_driver/devices/commissioning.h"

#include <algorithm>
#include <cstring>

#include "modbus_rtu_driver/core/config/link_config.h"

namespace modbus_rtu_driver {

TypeRegistry<CommissioningClass>& commissioningClasses() {
  static TypeRegistry<CommissioningClass> registry;  // built before the first add()
  return registry;
}

std::vector<CommissioningType> commissioningTypes() {
  std::vector<CommissioningType> out;
  const auto& registry = commissioningClasses();
  for (const DeviceDescriptor* type : registry.types())  // by name
    out.push_back({type, registry.find(type->name)->make});
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.commissioning->probeOrder() < b.commissioning->probeOrder();
  });
  return out;
}

const Commissioning* commissioningOf(const std::string& name) {
  const auto* entry = commissioningClasses().find(name);
  return entry ? entry->make : nullptr;
}

int baudOfCode(int code) {
  return code >= 0 && code < static_cast<int>(std::size(kStandardBauds)) ? kStandardBauds[code] : 0;
}

std::string baudCodeText(int code) {
  const int baud = baudOfCode(code);
  return baud ? std::to_string(baud) + " baud (code " + std::to_string(code) + ")"
              : "code " + std::to_string(code) + " (not a baud rate)";
}

DeviceConfig boardConfig(const DeviceDescriptor& type, int address) {
  DeviceConfig d;
  d.name = d.type = type.name;
  d.address = address;
  return d;
}

std::string parityCodeText(int code) {
  // The stored codes 0 none, 1 even, 2 odd are Parity's order (enum class Parity).
  return code >= 0 && code <= 2 ? std::string(parityName(static_cast<Parity>(code)))
                                : "code " + std::to_string(code);
}

// The defaults answer for a feature the type does not have: has() keeps the tool from asking.
Result Commissioning::unsupported() {
  return Result::failure(ErrorKind::kInvalidArgument, "not a setting of this device type");
}
Probe Commissioning::probeByRead(
    Transport& link, const Request& read,
    const std::function<void(const std::vector<uint16_t>& values, Probe* probe)>& judge) {
  Probe p;
  const Result r = link.execute(read);
  p.unclear = !answered(r);
  if (r.ok()) judge(r.values, &p);
  return p;
}
Result Commissioning::readAddress(Transport&, int, uint16_t*) const {
  return unsupported();
}
Result Commissioning::writeAddress(Transport&, int, uint16_t) const {
  return unsupported();
}
Result Commissioning::answersAt(Transport&, int) const {
  return unsupported();
}
Result Commissioning::readSetting(Transport&, int, BoardFeature, uint16_t*) const {
  return unsupported();
}
Result Commissioning::writeSetting(Transport&, int, BoardFeature, uint16_t) const {
  return unsupported();
}
std::string Commissioning::limitToRegister(size_t, double, uint16_t*, const std::string&) const {
  return "not a setting of this device type";
}
std::string Commissioning::checkLimits(const std::vector<uint16_t>&) const {
  return "not a setting of this device type";
}
Result Commissioning::readLimits(Transport&, int, std::vector<uint16_t>*) const {
  return unsupported();
}
Result Commissioning::writeLimits(Transport&, int, const std::vector<uint16_t>&) const {
  return unsupported();
}
Result Commissioning::factoryReset(Transport&, int) const {
  return unsupported();
}

}  // namespace modbus_rtu_driver
