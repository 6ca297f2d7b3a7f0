// The link a `port` names: a serial device (RtuLink), tcp://HOST:PORT (ModbusTcpLink) or
// rtu+tcp://HOST:PORT (RtuOverTcpLink). The config must be valid (validateLinkConfig).
#pragma once

#include <memory>

#include "modbus_rtu_driver/core/link/link.h"

namespace modbus_rtu_driver {

std::unique_ptr<Link> makeLink(const LinkConfig& config);

}  // namespace modbus_rtu_driver
