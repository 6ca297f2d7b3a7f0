#include "modbus_rtu_driver/core/link/make_link.h"

namespace modbus_rtu_driver {

std::unique_ptr<Link> makeLink(const LinkConfig& config, const LinkTarget& target) {
  if (!target.type) return makeLink(config);  // a config built by hand, its port not parsed yet
  return target.type->make(config, target);
}

std::unique_ptr<Link> makeLink(const LinkConfig& config) {
  LinkTarget target;
  if (!parseLinkTarget(config.port, &target, nullptr)) return nullptr;
  return makeLink(config, target);
}

}  // namespace modbus_rtu_driver
