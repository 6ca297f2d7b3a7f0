// The device types one layer knows (the driver's device classes, their ROS adapters, the
// simulated devices), each paired with that layer's factory. Each type's own source file adds
// itself when its library is loaded, as ros_canopen registers its profiles with class_loader:
//   const bool kRegistered = deviceClasses().add(kLd58a08Type, make);
// so a new type edits no shared table. The layer libraries are shared objects (catkin's default,
// and the sanitizer and fuzz builds build them shared too): every object file in them is loaded,
// with its registration, even though nothing refers to it by name.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/config/device_types.h"
#include "modbus_rtu_driver/core/modbus/text.h"

namespace modbus_rtu_driver {

template <typename Factory>
class TypeRegistry {
 public:
  struct Entry {
    const DeviceDescriptor* type;
    Factory make;
  };

  // Runs during static initialisation, before main: a name added twice is a programming error
  // (two files claiming one `type:`), reported and fatal there.
  bool add(const DeviceDescriptor& type, Factory make) {
    if (!entries_.emplace(type.name, Entry{&type, make}).second) {
      std::fprintf(stderr, "modbus_rtu_driver: device type '%s' is registered twice\n", type.name);
      std::abort();
    }
    return true;
  }
  // Null for a name no file registered.
  const Entry* find(const std::string& name) const {
    auto it = entries_.find(name);
    return it == entries_.end() ? nullptr : &it->second;
  }
  // In alphabetical order, the order messages list them in.
  std::vector<const DeviceDescriptor*> types() const {
    std::vector<const DeviceDescriptor*> out;
    out.reserve(entries_.size());
    for (const auto& kv : entries_) out.push_back(kv.second.type);
    return out;
  }
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    out.reserve(entries_.size());
    for (const auto& kv : entries_) out.push_back(kv.first);
    return out;
  }
  // "generic, lc_relay8, ..." for an error message.
  std::string nameList() const {
    return join(entries_, ", ", [](const auto& kv) { return kv.first; });
  }

 private:
  std::map<std::string, Entry> entries_;
};

}  // namespace modbus_rtu_driver
