#include "modbus_rtu_driver/ros/adapter_registry.h"

#include <cstring>

namespace modbus_rtu_driver {

namespace {
struct Entry {
  const char* type;
  AdapterFactory make;
};
const Entry kAdapters[] = {
    {"ld58a08", makeLd58a08Adapter},
    {"lc_relay8", makeLcRelay8Adapter},
    {"yespeed_pdu", makeYespeedPduAdapter},
    {"generic", makeGenericAdapter},
};
}  // namespace

std::unique_ptr<DeviceAdapter> createAdapter(std::shared_ptr<Device> device, BusScheduler& bus,
                                             const ros::NodeHandle& node) {
  for (const auto& e : kAdapters)
    if (std::strcmp(e.type, device->type()) == 0) return e.make(std::move(device), bus, node);
  return nullptr;
}

}  // namespace modbus_rtu_driver
