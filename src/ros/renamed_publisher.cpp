#include "modbus_rtu_driver/ros/renamed_publisher.h"

#include <mutex>
#include <set>

namespace modbus_rtu_driver {

void warnRenamed(const std::string& old_name, const std::string& name) {
  static std::mutex mutex;
  static std::set<std::string> warned;
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (!warned.insert(old_name).second) return;
  }
  ROS_WARN("%s is deprecated, use %s; removed in the next release", old_name.c_str(), name.c_str());
}

}  // namespace modbus_rtu_driver
