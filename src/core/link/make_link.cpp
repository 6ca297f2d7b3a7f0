#include "modbus_rtu_driver/core/link/make_link.h"

#include "modbus_rtu_driver/core/link/modbus_tcp_link.h"
#include "modbus_rtu_driver/core/link/rtu_link.h"
#include "modbus_rtu_driver/core/link/rtu_over_tcp_link.h"

namespace modbus_rtu_driver {

std::unique_ptr<Link> makeLink(const LinkConfig& config) {
  PortAddress address;
  parsePortAddress(config.port, &address, nullptr);
  switch (address.kind) {
    case PortKind::kModbusTcp:
      return std::make_unique<ModbusTcpLink>(config);
    case PortKind::kRtuOverTcp:
      return std::make_unique<RtuOverTcpLink>(config);
    case PortKind::kSerial:
      break;
  }
  return std::make_unique<RtuLink>(config);
}

}  // namespace modbus_rtu_driver
