// ROS face of one device: topics and services under ~/<device name>/, each message turned into a
// call of the device's DeviceUnit (runtime/device_unit.h), its state and fail-safe events into
// topics. The base class gives every device its outputs (state topics, command topics, SetBool
// per channel, SetOutputs); one small subclass per device type adds the rest. Device objects
// are only touched on the bus thread.
#pragma once

#include <diagnostic_updater/DiagnosticStatusWrapper.h>
#include <ros/ros.h>
#include <std_msgs/Bool.h>
#include <std_srvs/SetBool.h>

#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "modbus_rtu_driver/FailsafeEvent.h"
#include "modbus_rtu_driver/SetOutputs.h"
#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/core/bus/task_queue.h"
#include "modbus_rtu_driver/devices/device.h"
#include "modbus_rtu_driver/ros/digital_states_publisher.h"
#include "modbus_rtu_driver/ros/publish_shared.h"
#include "modbus_rtu_driver/runtime/bus_runtime.h"
#include "modbus_rtu_driver/runtime/device_unit.h"

namespace modbus_rtu_driver {

class DeviceAdapter {
 public:
  // `unit`: the device as the bus runtime composed it (runtime/device_unit.h), whose commands
  // the messages become; it outlives the adapter's bus work.
  DeviceAdapter(DeviceUnit& unit, BusScheduler& scheduler, const ros::NodeHandle& node);
  virtual ~DeviceAdapter() = default;
  DeviceAdapter(const DeviceAdapter&) = delete;
  DeviceAdapter& operator=(const DeviceAdapter&) = delete;

  // How state topics are published (every poll, or on change with a keep-alive); before start().
  void setPublishPolicy(const DigitalStatesPublisher::Policy& policy) { publish_policy_ = policy; }
  // Where the bus thread hands its publishing (the node's publishing thread, when the bus
  // thread runs at real-time priority); before start(). Without one, it publishes itself.
  void setPublishQueue(TaskQueue* queue) { publish_queue_ = queue; }
  // Advertises topics and services (the base's, then the type's own in advertise()), before the
  // runtime adds the polls, whose callbacks publish on them.
  void start();
  // Fills the device's /diagnostics status.
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  const std::string& name() const { return device_->name(); }

  // The stated safe time (BusRuntime::safeTime), for /diagnostics; before start().
  void setSafeTime(const SafeTime& t) { safe_time_ = t; }
  // Where fail-safe events go besides this device's topic (the node's latched ~failsafe).
  using EventSink = std::function<void(const FailsafeEvent&)>;
  void setFailsafeSink(EventSink sink) { failsafe_sink_ = std::move(sink); }

 protected:
  // The type's own topics and services (start() calls it before the first poll can run).
  virtual void advertise() {}
  // The configured and achieved poll rates in /diagnostics (the base: one poll per device).
  virtual void diagnosePollRate(diagnostic_updater::DiagnosticStatusWrapper& status,
                                const DeviceHealth& health);
  // The type's own lines in its /diagnostics status.
  virtual void diagnoseType(diagnostic_updater::DiagnosticStatusWrapper& status) { (void)status; }
  // Runs after each poll (`group`: a generic device's rate group) on the bus thread; the base
  // publishes outputs (and inputs).
  virtual void onPoll(size_t group, const Result& result);
  // Bus thread: a command or a safe write changed the device's state; the base publishes the
  // outputs.
  virtual void onChanged() { publishOutputs(); }
  // Bus thread only: publish the outputs message and the per-channel states that changed.
  void publishOutputs();
  // A poll's states on `publisher` (outputs_ or inputs_), now or on the publishing thread.
  void publishStates(DigitalStatesPublisher& publisher, const std::vector<bool>& states);
  // Bus thread: runs `task` (publishing) on the publishing thread, in the order posted. The
  // message is built from the device's state here; only ROS's part runs there.
  void publishLater(std::function<void()> task);
  template <class Message>
  void publishLater(const ros::Publisher& publisher, Message message) {
    publishLater([publisher, m = std::move(message)] { publishShared(publisher, m); });
  }
  // The device's command API (checked, queued, told to the fail-safe, read back).
  DeviceUnit& unit() { return unit_; }
  // Whether the last poll failed with the device now offline (its states are stale).
  bool offline() const { return !scheduler_.health(device_->name()).online; }
  // A fail-safe report, `text` its words: logged (stderr once ROS is down: at shutdown), on
  // `publisher` (~<device>/failsafe, latched; none before it is advertised) and the node's
  // ~failsafe.
  void publishReport(const FailsafeReport& report, const std::string& text,
                     const ros::Publisher& publisher);
  // "ok" or "<device>: <message>" for service answers.
  std::string answer(const Result& result, const std::string& what) const;

  DeviceUnit& unit_;
  std::shared_ptr<Device> device_;
  BusScheduler& scheduler_;
  ros::NodeHandle nh_;  // ~/<device>
  DigitalStatesPublisher::Policy publish_policy_;

 private:
  bool onSet(uint8_t channel, std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res);
  bool onSetOutputs(SetOutputs::Request& req, SetOutputs::Response& res);
  void onCommand(uint8_t channel, const std_msgs::Bool::ConstPtr& msg);
  void logOnlineChange(const DeviceHealth& health);
  virtual void diagnoseFailsafe(diagnostic_updater::DiagnosticStatusWrapper& status);

  EventSink failsafe_sink_;
  ros::Publisher failsafe_pub_;  // ~<device>/failsafe, latched: this device's newest event

  TaskQueue* publish_queue_ = nullptr;
  // Touched on the publishing thread only (through publishLater), once start() made them.
  std::unique_ptr<DigitalStatesPublisher> outputs_;
  std::unique_ptr<DigitalStatesPublisher> inputs_;  // devices with inputs only
  std::vector<ros::Subscriber> command_subs_;
  std::vector<ros::ServiceServer> services_;

  std::optional<bool> logged_online_;  // what the log last said
  std::optional<SafeTime> safe_time_;
  ros::WallTime last_offline_log_;
};

}  // namespace modbus_rtu_driver
