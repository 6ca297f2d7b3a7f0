// ROS face of one device: topics and services under ~/<device name>/. The base class gives every
// device its outputs (state topics, command topics, SetBool per channel, SetOutputs); one small
// subclass per device type adds the rest. All bus work goes through the BusScheduler; device
// objects are only touched on the bus thread.
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
#include "modbus_rtu_driver/core/bus/watchdog.h"
#include "modbus_rtu_driver/devices/device.h"
#include "modbus_rtu_driver/devices/failsafe.h"
#include "modbus_rtu_driver/failsafe/device_commands.h"
#include "modbus_rtu_driver/failsafe/device_failsafe.h"
#include "modbus_rtu_driver/failsafe/kept_timed_commands.h"
#include "modbus_rtu_driver/ros/digital_states_publisher.h"
#include "modbus_rtu_driver/ros/publish_shared.h"
#include "modbus_rtu_driver/ros/running_timed_parameter.h"

namespace modbus_rtu_driver {

class DeviceAdapter {
 public:
  DeviceAdapter(std::shared_ptr<Device> device, BusScheduler& scheduler,
                const ros::NodeHandle& node);
  virtual ~DeviceAdapter() = default;
  DeviceAdapter(const DeviceAdapter&) = delete;
  DeviceAdapter& operator=(const DeviceAdapter&) = delete;

  // How state topics are published (every poll, or on change with a keep-alive); before start().
  void setPublishPolicy(const DigitalStatesPublisher::Policy& policy) { publish_policy_ = policy; }
  // Where the bus thread hands its publishing (the node's publishing thread, when the bus
  // thread runs at real-time priority); before start(). Without one, it publishes itself.
  void setPublishQueue(TaskQueue* queue) { publish_queue_ = queue; }
  // Resumes the timed commands the previous node kept in `parameter` and keeps this node's
  // there; before the scheduler starts (the first poll compares with them). `parameter`
  // outlives the adapter's bus work.
  void keepTimedIn(RunningTimedParameter& parameter);
  // Advertises topics and services (the base's, then the type's own in advertise()), and only
  // then registers the poll with the scheduler: the bus may already run, and a poll's callback
  // publishes on them.
  void start();
  // Fills the device's /diagnostics status.
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  const std::string& name() const { return device_->name(); }
  uint8_t address() const { return device_->address(); }

  // Fail-safe: the decisions are DeviceFailsafe's (failsafe/device_failsafe.h); the adapter
  // hands it the triggers and publishes its reports. Where events go (the node's latched
  // ~failsafe topic).
  using EventSink = std::function<void(const FailsafeEvent&)>;
  void setFailsafeSink(EventSink sink) { failsafe_sink_ = std::move(sink); }
  // Puts the channels with a safe state there (only those in `only`, when given), confirmed by
  // reading the outputs back, and reports the event. The future holds the outcome.
  // Virtual: a generic device writes its signals' safe values instead (generic_adapter.cpp).
  virtual std::future<Result> applySafe(const std::string& trigger, const std::string& reason,
                                        const std::vector<uint8_t>& only = {}) {
    return failsafe_.applySafe(trigger, reason, only);
  }
  // Bus thread: a write to this device that the node carried for someone else (a share
  // client, a raw write) went out: confirmed by its reply, the fail-safe takes it as a
  // command; its answer lost, the channels it names are unknown until the next poll.
  void externalWrite(const Request& request, const Result& result, CommandSource source) {
    failsafe_.externalWrite(request, result, source);
  }
  // The bus-wide heartbeat (none: nullptr), for /diagnostics; before start().
  void setBusHeartbeat(const Watchdog* heartbeat, std::string topic) {
    failsafe_.setBusHeartbeat(heartbeat, std::move(topic));
  }
  // Timer (any thread): command deadlines that passed, this device's heartbeat.
  // Through applySafe: a generic device writes its safe values.
  void checkDeadlines() {
    for (const auto& f : failsafe_.firedTriggers()) applySafe(f.trigger, f.reason, f.only);
  }
  // Whether the device has any safe state, and whether start-up puts it there.
  virtual bool hasSafeStates() const { return failsafe_.hasSafeStates(); }
  bool safeOnStart() const { return failsafe_.config().on_start_safe && hasSafeStates(); }
  Watchdog* heartbeat() { return failsafe_.heartbeat(); }
  const FailsafeConfig& failsafeConfig() const { return failsafe_.config(); }

 protected:
  // The type's own topics and services (start() calls it before the first poll can run).
  virtual void advertise() {}
  // Registers the device's polls with the scheduler (the base: one, at the device's rate).
  virtual void addPolls();
  // The configured and achieved poll rates in /diagnostics (the base: one poll per device).
  virtual void diagnosePollRate(diagnostic_updater::DiagnosticStatusWrapper& status,
                                const DeviceHealth& health);
  // The type's own lines in its /diagnostics status.
  virtual void diagnoseType(diagnostic_updater::DiagnosticStatusWrapper& status) { (void)status; }
  // Runs after each poll on the bus thread; the base publishes outputs (and inputs).
  virtual void onPoll(const Result& result);
  // Runs `job` on the bus thread and waits for the real outcome. The message of a failure says
  // whether the device is offline.
  Result runOnBus(BusScheduler::Job job);
  // Bus thread only: publish the outputs message and the per-channel states that changed.
  void publishOutputs();
  // Bus thread: runs `task` (publishing) on the publishing thread, in the order posted. The
  // message is built from the device's state here; only ROS's part runs there.
  void publishLater(std::function<void()> task);
  template <class Message>
  void publishLater(const ros::Publisher& publisher, Message message) {
    publishLater([publisher, m = std::move(message)] { publishShared(publisher, m); });
  }
  // The device's commands on their way to the bus (failsafe/device_commands.h): writes, command
  // topics and timed commands, told to the fail-safe with their outcome.
  DeviceCommands& commands() { return commands_; }
  // Whether the last poll failed with the device now offline (its states are stale).
  bool offline() const { return !scheduler_.health(device_->name()).online; }
  // A fail-safe report, `text` its words: logged (stderr once ROS is down: at shutdown), on
  // `publisher` (~<device>/failsafe, latched; none before it is advertised) and the node's
  // ~failsafe.
  void publishReport(const FailsafeReport& report, const std::string& text,
                     const ros::Publisher& publisher);
  // "ok" or "<device>: <message>" for service answers.
  std::string answer(const Result& result, const std::string& what) const;

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

  DeviceFailsafe failsafe_;
  DeviceCommands commands_;  // after failsafe_: it calls into it
  EventSink failsafe_sink_;
  ros::Publisher failsafe_pub_;  // ~<device>/failsafe, latched: this device's newest event

  TaskQueue* publish_queue_ = nullptr;
  // Touched on the publishing thread only (through publishLater), once start() made them.
  std::unique_ptr<DigitalStatesPublisher> outputs_;
  std::unique_ptr<DigitalStatesPublisher> inputs_;  // devices with inputs only
  std::vector<ros::Subscriber> command_subs_;
  std::vector<ros::ServiceServer> services_;

  std::optional<bool> logged_online_;  // what the log last said
  ros::WallTime last_offline_log_;
};

}  // namespace modbus_rtu_driver
