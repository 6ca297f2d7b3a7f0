// DeviceAdapter's fail-safe: safe writes confirmed by read-back, restart handling, dead-man and
// heartbeat deadlines, and how the events are reported (log, ~failsafe, /diagnostics).
#include <diagnostic_msgs/DiagnosticStatus.h>

#include <cstdio>

#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/ros/device_adapter.h"

namespace modbus_rtu_driver {

namespace {

// "a, b": the names of the channels.
std::string channelNames(const std::vector<std::string>& names,
                         const std::vector<uint8_t>& channels) {
  return join(channels, ", ", [&names](uint8_t c) { return names[c]; });
}

std::future<Result> ready(Result r) {
  std::promise<Result> p;
  p.set_value(std::move(r));
  return p.get_future();
}

}  // namespace

std::future<Result> DeviceAdapter::applySafe(const std::string& trigger, const std::string& reason,
                                             const std::vector<uint8_t>& only) {
  const OutputTargets all = failsafe_.safeTargets();
  OutputTargets targets;
  for (size_t i = 0; i < all.channels.size(); ++i) {
    if (!only.empty() && std::find(only.begin(), only.end(), all.channels[i]) == only.end())
      continue;
    targets.channels.push_back(all.channels[i]);
    targets.states.push_back(all.states[i]);
  }
  if (targets.empty()) return ready(Result::success());
  // A trigger that lasts keeps these channels safe on every restore until a user commands them
  // again, even if this write does not get through.
  if (trigger == "heartbeat" || trigger == "command_timeout") failsafe_.holdSafe(targets.channels);
  return bus_.submit(device_->name(), [this, targets, trigger, reason](Transport& t) {
    return writeAndReport(t, targets, trigger, reason, "safe", true);
  });
}

Result DeviceAdapter::writeAndReport(Transport& t, const OutputTargets& targets,
                                     const std::string& trigger, const std::string& reason,
                                     const std::string& action, bool holds_safe_states) {
  const auto names = device_->outputNames();
  FailsafeEvent e;
  e.header.stamp = ros::Time::now();
  e.device = device_->name();
  e.trigger = trigger;
  e.reason = reason;
  e.action = action;
  for (size_t i = 0; i < targets.channels.size(); ++i) {
    e.channels.push_back(names[targets.channels[i]]);
    e.states.push_back(targets.states[i]);
  }
  Result w = device_->setOutputs(t, targets.channels, targets.states);
  failsafe_.observeWrite(device_->outputs());
  if (w.ok()) {
    // Read back: the outputs as the device reports them now, not as the write's echo said.
    const Result back = device_->poll(t);
    if (!back.ok()) {
      w = Result::failure(back.error, "written, but reading back failed: " + back.message);
    } else {
      failsafe_.observeWrite(device_->outputs());
      for (size_t i = 0; i < targets.channels.size(); ++i) {
        if (device_->outputs()[targets.channels[i]] == targets.states[i]) continue;
        w = Result::failure(ErrorKind::kMalformed, "read back: " + names[targets.channels[i]] +
                                                       " is still " +
                                                       (targets.states[i] ? "off" : "on"));
        break;
      }
    }
  }
  if (w.ok()) {
    // A safe write is a command like any other: a restore writes it again.
    failsafe_.confirmed(targets.channels, targets.states, FailsafeTracker::Writer::kFailsafe);
    publishOutputs();
    // A restore with no channel held safe put back what users had: no longer in a safe state.
    if (action == "restore" && !failsafe_.anyHeldSafe()) endFailsafeState();
  }
  // A safe state not reached is tried again when the device answers again.
  if (holds_safe_states) failsafe_.setSafePending(!w.ok());
  e.confirmed = w.ok();
  e.message = w.ok() ? "confirmed by reading the outputs back" : w.message;
  report(e);
  return w;
}

void DeviceAdapter::checkRestart() {
  // The scheduler records this poll after this callback: health still says how it was before.
  const bool was_offline = !bus_.health(device_->name()).online;
  std::vector<bool> timed(device_->outputCount());
  for (size_t i = 0; i < timed.size(); ++i) timed[i] = device_->outputSelfTimed(i);
  std::vector<uint8_t> changed;
  const auto verdict = failsafe_.observePoll(device_->outputs(), timed, was_offline, &changed);
  // A share client or raw write changed outputs: "in their safe state" (which names the channels
  // the safe write set) is no longer true, as after a user's write.
  if (failsafe_.tookExternalWrite()) endFailsafeState();
  const bool pending = failsafe_.safePending();
  if (verdict == FailsafeTracker::Verdict::kNormal && !pending) return;
  std::string reason = "the device answers again; its safe state was not reached before";
  std::string action = "safe";
  if (verdict != FailsafeTracker::Verdict::kNormal) {
    std::lock_guard<std::mutex> lock(failsafe_mutex_);
    ++restarts_detected_;
    reason = verdict == FailsafeTracker::Verdict::kCameBack
                 ? "answered again after being offline"
                 : "outputs " + channelNames(device_->outputNames(), changed) +
                       " changed with no command in between (power cycle?)";
    const OnRestart policy = failsafe_.config().on_restart;
    // With on_restart: leave, only the pending safe states are written: say so.
    action = pending && policy == OnRestart::kLeave ? "safe" : onRestartName(policy);
  }
  const OutputTargets targets = failsafe_.afterPollTargets(verdict);
  if (targets.empty()) {
    FailsafeEvent e;
    e.header.stamp = ros::Time::now();
    e.device = device_->name();
    e.trigger = "restart";
    e.reason = reason;
    e.action = action;
    e.confirmed = true;
    e.message = "outputs left as they are";
    report(e);
    return;
  }
  // The pending safe states are in this write (afterPollTargets), as are on_restart: safe's.
  const bool holds_safe_states = pending || action == "safe";
  bus_.submit(device_->name(), [this, targets, reason, action, holds_safe_states](Transport& t) {
    return writeAndReport(t, targets, "restart", reason, action, holds_safe_states);
  });
}

void DeviceAdapter::checkDeadlines() {
  const auto expired = failsafe_.expiredCommands();
  if (!expired.empty())
    applySafe("command_timeout",
              "no command on " + channelNames(device_->outputNames(), expired) +
                  " within its command_timeout",
              expired);
  if (heartbeat_ && heartbeat_->expired()) {
    const FailsafeConfig& fs = failsafe_.config();
    applySafe("heartbeat", "no message on " + fs.heartbeat_topic + " within " +
                               numberText(fs.heartbeat_timeout) + " s");
  }
}

void DeviceAdapter::report(const FailsafeEvent& e) {
  std::string text = e.trigger + " (" + e.reason + "): ";
  std::vector<std::string> changes;
  for (size_t i = 0; i < e.channels.size(); ++i)
    changes.push_back(e.channels[i] + (e.states[i] ? " on" : " off"));
  text += join(changes);
  if (e.channels.empty()) text += e.action;
  text += e.confirmed ? "" : "; NOT confirmed: " + e.message;
  {
    std::lock_guard<std::mutex> lock(failsafe_mutex_);
    ++failsafe_events_;
    last_failsafe_ = text;
    if (!e.channels.empty() && e.action == "safe") failsafe_active_ = text;
  }
  if (!ros::ok()) {
    // Shutting down: rosconsole is gone, and this is what the user must still see.
    std::fprintf(stderr, "[%s] %s: fail-safe %s\n", e.confirmed ? "WARN" : "ERROR",
                 device_->name().c_str(), text.c_str());
  } else if (e.confirmed) {
    ROS_WARN("%s: fail-safe %s", device_->name().c_str(), text.c_str());
  } else {
    ROS_ERROR("%s: fail-safe %s", device_->name().c_str(), text.c_str());
  }
  // ~<device>/failsafe keeps this device's newest event for late subscribers; ~failsafe
  // carries every device's events.
  if (failsafe_pub_) publishLater(failsafe_pub_, e);
  if (failsafe_sink_) failsafe_sink_(e);
}

void DeviceAdapter::externalWrite(const Request& request) {
  failsafe_.externalWrite(device_->outputsWrittenBy(request));
}

void DeviceAdapter::endFailsafeState() {
  std::lock_guard<std::mutex> lock(failsafe_mutex_);
  failsafe_active_.clear();
}

void DeviceAdapter::diagnoseFailsafe(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const FailsafeConfig& fs = failsafe_.config();
  const auto names = device_->outputNames();
  std::vector<std::string> states;
  for (size_t i = 0; i < names.size(); ++i)
    if (fs.safeStateOf(i) != SafeState::kHold)
      states.push_back(names[i] + " " + safeStateName(fs.safeStateOf(i)));
  const std::string safe = join(states);
  status.add("safe states", safe.empty() ? "none (every output holds)" : safe);
  status.add("on_restart", onRestartName(fs.on_restart));
  std::lock_guard<std::mutex> lock(failsafe_mutex_);
  status.add("restarts detected", restarts_detected_);
  status.add("fail-safe events", failsafe_events_);
  status.add("last fail-safe event", last_failsafe_.empty() ? "none" : last_failsafe_);
  if (!failsafe_active_.empty())
    status.mergeSummary(diagnostic_msgs::DiagnosticStatus::WARN,
                        "outputs in their safe state after " + failsafe_active_);
}

}  // namespace modbus_rtu_driver
