#include "modbus_rtu_driver/ros/yaml_params.h"

#include <sstream>

namespace modbus_rtu_driver {

YAML::Node toYaml(XmlRpc::XmlRpcValue& v) {
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return YAML::Node(static_cast<bool>(v));
    case XmlRpc::XmlRpcValue::TypeInt:
      return YAML::Node(static_cast<int>(v));
    case XmlRpc::XmlRpcValue::TypeDouble: {
      // Keep full precision: YAML::Node(double) would print with default stream precision.
      std::ostringstream s;
      s.precision(17);
      s << static_cast<double>(v);
      return YAML::Node(s.str());
    }
    case XmlRpc::XmlRpcValue::TypeString:
      return YAML::Node(static_cast<std::string>(v));
    case XmlRpc::XmlRpcValue::TypeArray: {
      YAML::Node list(YAML::NodeType::Sequence);
      for (int i = 0; i < v.size(); ++i) list.push_back(toYaml(v[i]));
      return list;
    }
    case XmlRpc::XmlRpcValue::TypeStruct: {
      YAML::Node map(YAML::NodeType::Map);
      for (auto& kv : v) map[kv.first] = toYaml(kv.second);
      return map;
    }
    default:
      return YAML::Node();
  }
}

}  // namespace modbus_rtu_driver
