// Parameters arrive as XmlRpc values; the core checks configuration as YAML. This converts one
// into the other so the same rules (and their unit tests) apply to launch files and YAML.
#pragma once

#include <XmlRpcValue.h>
#include <yaml-cpp/yaml.h>

namespace modbus_rtu_driver {

YAML::Node toYaml(XmlRpc::XmlRpcValue& value);

}  // namespace modbus_rtu_driver
