// ROS face of one device: topics and services under ~/<device name>/. The base class gives every
// device its outputs (state topics, command topics, SetBool per channel, SetOutputs); one small
// subclass per device type adds the rest. All bus work goes through the BusScheduler; device
// objects are only touched on the bus thread.
#pragma once

#include <diagnostic_updater/DiagnosticStatusWrapper.h>
#include <ros/ros.h>
#include <std_msgs/Bool.h>
#include <std_srvs/SetBool.h>

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "modbus_rtu_driver/SetOutputs.h"
#include "modbus_rtu_driver/core/bus_scheduler.h"
#include "modbus_rtu_driver/devices/device.h"
#include "modbus_rtu_driver/devices/output_batch.h"
#include "modbus_rtu_driver/ros/digital_states_publisher.h"

namespace modbus_rtu_driver {

class DeviceAdapter {
 public:
  DeviceAdapter(std::shared_ptr<Device> device, BusScheduler& bus, const ros::NodeHandle& node);
  virtual ~DeviceAdapter() = default;
  DeviceAdapter(const DeviceAdapter&) = delete;
  DeviceAdapter& operator=(const DeviceAdapter&) = delete;

  // How state topics are published (every poll, or on change with a keep-alive); before start().
  void setPublishPolicy(const DigitalStatesPublisher::Policy& policy) { publish_policy_ = policy; }
  // Advertises topics and services and registers the poll with the scheduler.
  virtual void start();
  // Fills the device's /diagnostics status.
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  const std::string& name() const { return device_->name(); }

 protected:
  // Runs after each poll on the bus thread; the base publishes outputs.
  virtual void onPoll(const Result& result);
  // Runs `job` on the bus thread and waits for the real outcome. The message of a failure says
  // whether the device is offline.
  Result runOnBus(BusScheduler::Job job);
  // Bus thread only: publish the outputs message and the per-channel states that changed.
  void publishOutputs();
  // Whether the last poll failed with the device now offline (its states are stale).
  bool offline() const { return !bus_.health(device_->name()).online; }
  // Service writes of outputs: checked, then merged with others queued for this device.
  Result writeOutputs(const std::vector<uint8_t>& channels, const std::vector<bool>& states);
  // "ok" or "<device>: <message>" for service answers.
  std::string answer(const Result& result, const std::string& what) const;

  std::shared_ptr<Device> device_;
  BusScheduler& bus_;
  ros::NodeHandle nh_;  // ~/<device>
  DigitalStatesPublisher::Policy publish_policy_;

 private:
  bool onSet(uint8_t channel, std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res);
  bool onSetOutputs(SetOutputs::Request& req, SetOutputs::Response& res);
  void onCommand(uint8_t channel, const std_msgs::Bool::ConstPtr& msg);
  void logOnlineChange(const DeviceHealth& health);

  std::unique_ptr<DigitalStatesPublisher> outputs_;
  std::vector<ros::Subscriber> command_subs_;
  std::vector<ros::ServiceServer> services_;

  std::optional<bool> logged_online_;  // what the log last said
  ros::WallTime last_offline_log_;

  OutputBatch batch_;
  // Command topics: newest command per channel wins; one bus job drains them.
  std::mutex commands_mutex_;
  std::vector<std::optional<bool>> pending_commands_;
  bool commands_queued_ = false;
};

}  // namespace modbus_rtu_driver
