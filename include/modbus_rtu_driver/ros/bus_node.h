// One node per bus (a serial port or a gateway): reads the configuration from the private
// namespace, opens the link, and runs the bus's BusRuntime (runtime/bus_runtime.h: the bus
// thread, the devices, their fail-safe, the share), with one ROS adapter per device; it turns
// ROS messages and timers into the runtime's calls and reports to /diagnostics.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>

#include <chrono>
#include <cstdio>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/bus/task_queue.h"
#include "modbus_rtu_driver/core/link/link.h"
#include "modbus_rtu_driver/node_config/bus_config.h"
#include "modbus_rtu_driver/ros/device_adapter.h"
#include "modbus_rtu_driver/ros/raw_writes.h"
#include "modbus_rtu_driver/ros/running_timed_parameter.h"
#include "modbus_rtu_driver/ros/share_bridge.h"
#include "modbus_rtu_driver/runtime/bus_runtime.h"

namespace modbus_rtu_driver {

class BusNode {
 public:
  // The spinner's threads (bus_node_main.cpp): at most this many service calls wait on the bus
  // at once, each with one write queued (the safe time counts them ahead of a safe write).
  static constexpr int kServiceThreads = 4;
  explicit BusNode(const ros::NodeHandle& private_nh);
  ~BusNode();
  // False (with the reason logged once) when the configuration is invalid.
  bool start();
  // Puts outputs with a safe state there (confirmed, within shutdown_timeout), then stops the
  // bus. Call after ROS has shut down; the destructor stops the bus without it.
  void shutdown();

 private:
  void diagnoseBus(diagnostic_updater::DiagnosticStatusWrapper& status);
  // Fail-safe: ~failsafe, heartbeat subscriptions (any type), the deadline timer.
  void startFailsafe();
  uint64_t recentLineErrors(const LinkStats& stats);
  // realtime_priority and lock_memory: asked for here, their outcome shown in the diagnostics.
  BusScheduler::Options schedulingOptions();
  // Where the bus thread's ROS publishing goes: the publishing thread, or none (itself).
  TaskQueue* rosPublishing() const;
  // wire_log: opens the file and has the link report every frame to it.
  bool openWireLog(std::string* error);
  // Logs each device's safe time and hands it to its /diagnostics.
  void stateSafeTimes();

  static constexpr int kErrorWindowSeconds = 10;
  // After shutdown_timeout, how long the stop still waits for the bus thread to end the
  // transaction it is in before the process exits without it (docs/failsafe.md).
  static constexpr std::chrono::seconds kBusStopGrace{2};
  // After the bus thread ended, how long the stop waits for ~running_timed's last writes.
  static constexpr std::chrono::seconds kParameterGrace{1};
  std::deque<std::pair<ros::WallTime, uint64_t>> error_totals_;  // (when, line errors so far)
  void logRecoveries();
  std::string silentBusAdvice() const;
  uint64_t logged_reopens_ = 0;     // port reopens already logged (diagnostics thread)
  bool logged_all_silent_ = false;  // "no device answers" logged and not yet over

  ros::NodeHandle nh_;
  BusConfig config_;
  std::unique_ptr<Link> link_;  // serial, Modbus TCP or RTU over TCP (by `port`)
  // Declared before the runtime, which keeps the timed commands in it: it outlives it.
  std::unique_ptr<RunningTimedParameter> running_timed_;
  std::vector<std::unique_ptr<DeviceAdapter>> adapters_;
  // The bus composed (runtime/bus_runtime.h); destroyed first (~BusNode), as its bus thread
  // calls into the adapters.
  std::unique_ptr<BusRuntime> runtime_;
  // wire_log's writes, and with realtime_priority the bus thread's publishing, run here; none
  // without either (stopped after the bus, before the adapters go).
  std::unique_ptr<TaskQueue> publish_queue_;
  std::unique_ptr<FILE, int (*)(FILE*)> wire_log_{nullptr, &std::fclose};  // publishing thread
  std::unique_ptr<RawWrites> raw_writes_;
  std::unique_ptr<ShareBridge> share_;  // the runtime's share's listening and /diagnostics
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::Timer diagnostics_timer_;
  ros::Publisher failsafe_pub_;
  std::vector<ros::Subscriber> heartbeat_subs_;
  ros::SteadyTimer failsafe_timer_;
  std::mutex realtime_mutex_;  // the two below: set on the bus thread, read by diagnostics
  std::string realtime_status_ = "off";
  std::string memory_status_ = "not locked";
};

}  // namespace modbus_rtu_driver
