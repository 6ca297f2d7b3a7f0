#include "modbus_rtu_driver/ros/device_adapter.h"

#include <diagnostic_msgs/DiagnosticStatus.h>

#include <cstdio>

#include "modbus_rtu_driver/core/config/number_text.h"

namespace modbus_rtu_driver {

DeviceAdapter::DeviceAdapter(DeviceUnit& unit, BusScheduler& scheduler, const ros::NodeHandle& node)
    : unit_(unit), device_(unit.sharedDevice()), scheduler_(scheduler), nh_(node, device_->name()) {
  // Here, not in start(): the start-up safe states are reported before start(). Latched: this
  // device's newest event, for a late subscriber.
  if (device_->outputCount() > 0 || unit_.hasSafeStates())
    failsafe_pub_ = nh_.advertise<FailsafeEvent>("failsafe", 1, true);
  DeviceUnit::Observers o;
  o.polled = [this](size_t group, const Result& r) { onPoll(group, r); };
  o.changed = [this] { onChanged(); };
  o.report = [this](const FailsafeReport& r, const std::string& text) {
    publishReport(r, text, failsafe_pub_);
  };
  unit_.observe(std::move(o));
}

void DeviceAdapter::start() {
  const auto names = device_->outputNames();
  const size_t n = device_->outputCount();
  // A device without outputs (a generic sensor) gets no outputs topic and no set_outputs.
  if (n > 0)
    outputs_ = std::make_unique<DigitalStatesPublisher>(nh_, "outputs", names, publish_policy_);
  if (device_->inputCount() > 0)
    inputs_ = std::make_unique<DigitalStatesPublisher>(nh_, "inputs", device_->inputNames(),
                                                       publish_policy_);
  for (size_t i = 0; i < n; ++i) {
    const auto ch = static_cast<uint8_t>(i);
    command_subs_.push_back(nh_.subscribe<std_msgs::Bool>(
        names[i] + "/command", 10,
        [this, ch](const std_msgs::Bool::ConstPtr& msg) { onCommand(ch, msg); }));
    services_.push_back(
        nh_.advertiseService<std_srvs::SetBool::Request, std_srvs::SetBool::Response>(
            names[i] + "/set",
            [this, ch](std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res) {
              return onSet(ch, req, res);
            }));
  }
  if (n > 0)
    services_.push_back(nh_.advertiseService("set_outputs", &DeviceAdapter::onSetOutputs, this));
  advertise();
}

void DeviceAdapter::onPoll(size_t /*group*/, const Result& result) {
  if (result.ok()) {
    publishOutputs();
    if (inputs_) publishStates(*inputs_, device_->inputs());
  } else if (offline()) {
    publishLater([this] {
      if (outputs_) outputs_->markStale();
      if (inputs_) inputs_->markStale();
    });
  }
}

void DeviceAdapter::publishLater(std::function<void()> task) {
  postOrRun(publish_queue_, std::move(task));
}

void DeviceAdapter::publishOutputs() {
  if (!outputs_) return;  // before start(): the start-up safe states
  publishStates(*outputs_, device_->outputs());
}

void DeviceAdapter::publishStates(DigitalStatesPublisher& publisher,
                                  const std::vector<bool>& states) {
  // Without a publishing thread (the default) the states are published here, from the device's
  // own: no copy and no task a poll (issue 50). With one, a copy goes to it.
  if (!publish_queue_) return publisher.publish(states, ros::Time::now());
  publishLater(
      [&publisher, states, stamp = ros::Time::now()] { publisher.publish(states, stamp); });
}

std::string DeviceAdapter::answer(const Result& result, const std::string& what) const {
  if (result.ok()) return result.message.empty() ? what : what + " (" + result.message + ")";
  std::string msg = device_->name() + ": " + result.message;
  if (result.error != ErrorKind::kInvalidArgument && !scheduler_.online(device_->name()))
    msg += " (device is offline)";
  return msg;
}

bool DeviceAdapter::onSet(uint8_t channel, std_srvs::SetBool::Request& req,
                          std_srvs::SetBool::Response& res) {
  const bool state = req.data;
  const Result r = unit_.set({channel}, {state}).get();
  res.success = r.ok();
  res.message = answer(r, device_->outputNames()[channel] + (state ? " on" : " off"));
  return true;
}

bool DeviceAdapter::onSetOutputs(SetOutputs::Request& req, SetOutputs::Response& res) {
  std::vector<uint8_t> channels(req.channels.begin(), req.channels.end());
  std::vector<bool> states(req.states.begin(), req.states.end());
  const Result r = unit_.set(channels, states).get();
  res.success = r.ok();
  res.message = answer(r, std::to_string(channels.size()) + " output(s) set");
  return true;
}

// Commands join the same batch as service writes (newest state per channel wins, one frame); a
// topic's caller gets no answer, so a write that failed is logged.
void DeviceAdapter::onCommand(uint8_t channel, const std_msgs::Bool::ConstPtr& msg) {
  unit_.command(channel, msg->data, {0, [this](const Result& w) {
                                       if (!w.ok())
                                         ROS_WARN_THROTTLE(1.0, "%s: command failed: %s",
                                                           device_->name().c_str(),
                                                           w.message.c_str());
                                     }});
}

// Going offline and coming back are logged when they happen, and an offline device again every
// 30 s (throttled per device: the ROS_*_THROTTLE macros throttle per call site).
void DeviceAdapter::logOnlineChange(const DeviceHealth& h) {
  const ros::WallTime now = ros::WallTime::now();
  if (h.online) {
    if (!logged_online_.value_or(true))
      ROS_INFO("%s: back online after %s offline", device_->name().c_str(),
               secondsText(h.last_offline_seconds).c_str());
    logged_online_ = true;
    return;
  }
  if (logged_online_.value_or(true) || (now - last_offline_log_).toSec() >= 30.0) {
    ROS_WARN("%s (%s @%d): offline: %s", device_->name().c_str(), device_->type(),
             device_->config().address, h.last_error.c_str());
    last_offline_log_ = now;
  }
  logged_online_ = false;
}

void DeviceAdapter::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const DeviceHealth h = scheduler_.health(device_->name());
  using diagnostic_msgs::DiagnosticStatus;
  logOnlineChange(h);
  if (!h.online) {
    status.summary(DiagnosticStatus::ERROR, "offline: " + h.last_error);
  } else if (!h.answered) {
    status.summary(DiagnosticStatus::WARN, "not heard from yet");
  } else if (h.rate_overrun) {
    status.summary(DiagnosticStatus::WARN, "bus cannot keep the configured poll rate");
  } else if (h.consecutive_failures > 0) {
    status.summary(DiagnosticStatus::WARN, "last transaction failed: " + h.last_error);
  } else {
    status.summary(DiagnosticStatus::OK, "online");
  }
  status.hardware_id = device_->type() + std::string(" @") + std::to_string(device_->address());
  status.add("type", device_->type());
  status.add("address", device_->config().address);
  status.add("online", h.online && h.answered);
  diagnosePollRate(status, h);
  status.add("polls ok", h.polls_ok);
  status.add("polls failed", h.polls_failed);
  status.add("writes ok", h.writes_ok);
  status.add("writes failed", h.writes_failed);
  status.add("writes refused unsent (port not open)", h.writes_refused);
  status.add("shared requests ok", h.shared_ok);  // Modbus TCP clients of the share
  status.add("shared requests failed", h.shared_failed);
  status.add("consecutive failures", h.consecutive_failures);
  status.add("last error", h.last_error.empty() ? "none" : h.last_error);
  // docs/failsafe.md, "How long until safe".
  if (safe_time_) status.add("safe within [s]", safe_time_->total());
  diagnoseFailsafe(status);
  diagnoseType(status);
}

void DeviceAdapter::diagnosePollRate(diagnostic_updater::DiagnosticStatusWrapper& status,
                                     const DeviceHealth& health) {
  status.add("poll rate configured [Hz]", device_->config().poll_rate);
  status.add("poll rate achieved [Hz]", health.achieved_poll_rate);
}

// The fail-safe's report: the log (stderr once ROS is down: at shutdown, rosconsole is gone and
// this is what the user must still see), ~<device>/failsafe (this device's newest event, for
// late subscribers) and the node's ~failsafe (every device's events).
void DeviceAdapter::publishReport(const FailsafeReport& r, const std::string& text,
                                  const ros::Publisher& publisher) {
  if (!ros::ok()) {
    std::fprintf(stderr, "[%s] %s: fail-safe %s\n", r.confirmed ? "WARN" : "ERROR",
                 device_->name().c_str(), text.c_str());
  } else if (r.note_only) {
    ROS_INFO("%s: restart detected (%s); on_restart: leave", device_->name().c_str(),
             r.reason.c_str());
  } else if (r.confirmed) {
    ROS_WARN("%s: fail-safe %s", device_->name().c_str(), text.c_str());
  } else {
    ROS_ERROR("%s: fail-safe %s", device_->name().c_str(), text.c_str());
  }
  FailsafeEvent e;
  e.header.stamp = ros::Time::now();
  e.device = r.device;
  e.trigger = triggerName(r.trigger);
  e.reason = r.reason;
  e.action = actionName(r.action);
  e.channels = r.channels;
  e.states.assign(r.states.begin(), r.states.end());
  e.values = r.values;
  e.confirmed = r.confirmed;
  e.message = r.message;
  if (publisher) publishLater(publisher, e);
  if (failsafe_sink_) failsafe_sink_(e);
}

void DeviceAdapter::diagnoseFailsafe(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const FailsafeStatus s = unit_.failsafe().status();
  status.add("safe states", s.safe_states);
  status.add("on_restart", s.on_restart);
  if (s.bus_heartbeat_lost) status.add("bus heartbeat", *s.bus_heartbeat_lost ? "lost" : "alive");
  if (s.device_heartbeat_lost)
    status.add("device heartbeat", *s.device_heartbeat_lost ? "lost" : "alive");
  status.add("held safe until commanded", s.held);
  status.add("safe writes owed", s.owed);
  status.add("restarts detected", s.restarts_detected);
  status.add("fail-safe events", s.events);
  status.add("last fail-safe event", s.last_event);
  if (!s.warn.empty()) status.mergeSummary(diagnostic_msgs::DiagnosticStatus::WARN, s.warn);
}

}  // namespace modbus_rtu_driver
