// The link a `port` names, made by its kind's factory (core/link/link_types.h: each kind
// registers itself from its own file).
#pragma once

#include <memory>

#include "modbus_rtu_driver/core/link/link.h"

namespace modbus_rtu_driver {

// `config` is valid and `target` its port, parsed (validateLink gives both); a target without a
// type (a config built by hand) is parsed from config.port.
std::unique_ptr<Link> makeLink(const LinkConfig& config, const LinkTarget& target);
// Parses config.port first; null when it does not parse (validateLink says why).
std::unique_ptr<Link> makeLink(const LinkConfig& config);

}  // namespace modbus_rtu_driver
