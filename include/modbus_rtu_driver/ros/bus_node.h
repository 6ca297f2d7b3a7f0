// One node per serial bus: reads the configuration from the private namespace, owns the link,
// the bus thread and every device on it, and reports to /diagnostics.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>

#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/bus_config.h"
#include "modbus_rtu_driver/core/bus_scheduler.h"
#include "modbus_rtu_driver/core/rtu_link.h"
#include "modbus_rtu_driver/ros/device_adapter.h"
#include "modbus_rtu_driver/ros/raw_writes.h"

namespace modbus_rtu_driver {

class BusNode {
 public:
  explicit BusNode(const ros::NodeHandle& private_nh);
  ~BusNode();
  // False (with the reason logged once) when the configuration is invalid.
  bool start();

 private:
  void diagnoseBus(diagnostic_updater::DiagnosticStatusWrapper& status);
  uint64_t recentLineErrors(const LinkStats& stats);

  static constexpr int kErrorWindowSeconds = 10;
  std::deque<std::pair<ros::WallTime, uint64_t>> error_totals_;  // (when, line errors so far)

  ros::NodeHandle nh_;
  BusConfig config_;
  std::unique_ptr<RtuLink> link_;
  std::unique_ptr<BusScheduler> bus_;
  std::vector<std::unique_ptr<DeviceAdapter>> adapters_;
  std::unique_ptr<RawWrites> raw_writes_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::Timer diagnostics_timer_;
};

}  // namespace modbus_rtu_driver
