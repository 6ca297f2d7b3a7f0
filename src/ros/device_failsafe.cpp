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
  // A trigger that lasts holds its channels safe on every restore until they are commanded
  // again, even if this write does not get through; what the write sets is read from the holds
  // when the bus gets to it, so a channel commanded in between is left as commanded.
  const bool lasting = trigger == "heartbeat" || trigger == "command_timeout";
  const auto since = failsafe_.clock().now();
  OutputTargets targets;
  if (lasting) {
    failsafe_.hold(only,
                   trigger == "heartbeat" ? HoldTrigger::kHeartbeat : HoldTrigger::kCommandTimeout);
    targets = failsafe_.heldTargets(only);
  } else {
    const OutputTargets all = failsafe_.safeTargets();
    for (size_t i = 0; i < all.channels.size(); ++i) {
      if (!only.empty() && std::find(only.begin(), only.end(), all.channels[i]) == only.end())
        continue;
      targets.channels.push_back(all.channels[i]);
      targets.states.push_back(all.states[i]);
    }
  }
  if (targets.empty()) return ready(Result::success());
  return bus_.submit(device_->name(),
                     [this, lasting, only, targets, trigger, reason, since](Transport& t) {
                       const OutputTargets now = lasting ? failsafe_.heldTargets(only) : targets;
                       if (now.empty())
                         return Result::success();  // commanded again before the bus got to it
                       return writeAndReport(t, now, trigger, reason, "safe", since);
                     });
}

Result DeviceAdapter::writeAndReport(Transport& t, const OutputTargets& targets,
                                     const std::string& trigger, const std::string& reason,
                                     const std::string& action,
                                     std::optional<Clock::time_point> owe_since) {
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
  failsafe_.writeRan();
  Result w = device_->setOutputs(t, targets.channels, targets.states);
  if (w.ok()) {
    // Read back: the outputs as the device reports them now, not as the write's echo said.
    const Result back = device_->poll(t);
    if (!back.ok()) {
      w = Result::failure(back.error, "written, but reading back failed: " + back.message);
    } else {
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
    failsafe_.commanded(targets.channels, targets.states,
                        action == "restore" ? CommandSource::kRestore : CommandSource::kSafe);
    publishOutputs();
    // A restore with no channel held safe put back what users had: no longer in a safe state.
    if (action == "restore" && !failsafe_.anyHeld()) endFailsafeState();
  } else if (owe_since) {
    // Owed per channel: written when the device answers again, unless commanded before that.
    failsafe_.owe(targets, *owe_since, trigger);
  }
  e.confirmed = w.ok();
  e.message = w.ok() ? "confirmed by reading the outputs back" : w.message;
  report(e);
  return w;
}

void DeviceAdapter::timedCommandDone(const TimedIntent& intent, const Result& result) {
  if (result.ok()) {
    failsafe_.timed(intent, CommandSource::kTimed);
    endFailsafeState();
    return;
  }
  // Not confirmed: it may run or not. Either level may show until its end, then its final one
  // is what a poll finds (it is not taken as commanded: the caller was told it failed).
  TimedIntent unsure = intent;
  unsure.during.reset();
  failsafe_.timed(unsure, CommandSource::kFound);
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
  if (failsafe_.tookAdoptedWrite()) endFailsafeState();
  const bool owed = !failsafe_.owed().empty();
  if (verdict == ChannelIntents::Verdict::kNormal && !owed) return;
  std::string reason = "the device answers again; its safe state was not reached before";
  std::string action = "safe";
  if (verdict != ChannelIntents::Verdict::kNormal) {
    std::lock_guard<std::mutex> lock(failsafe_mutex_);
    ++restarts_detected_;
    reason = verdict == ChannelIntents::Verdict::kCameBack
                 ? "answered again after being offline"
                 : "outputs " + channelNames(device_->outputNames(), changed) +
                       " changed with no command in between (power cycle?)";
    const OnRestart policy = failsafe_.config().on_restart;
    // With on_restart: leave, only the owed safe states are written: say so.
    action = owed && policy == OnRestart::kLeave ? "safe" : onRestartName(policy);
  }
  // What to write is read when the write runs: a command confirmed before then is not undone.
  bus_.submit(device_->name(), [this, verdict, reason, action](Transport& t) {
    const OutputTargets targets = failsafe_.afterPollTargets(verdict);
    if (targets.empty()) {
      if (verdict == ChannelIntents::Verdict::kNormal) return Result::success();
      FailsafeEvent e;
      e.header.stamp = ros::Time::now();
      e.device = device_->name();
      e.trigger = "restart";
      e.reason = reason;
      e.action = action;
      e.confirmed = true;
      e.message = "outputs left as they are";
      report(e);
      return Result::success();
    }
    return writeAndReport(t, targets, "restart", reason, action, std::nullopt);
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

std::string DeviceAdapter::lostHeartbeat() const {
  if (bus_heartbeat_ && bus_heartbeat_->tripped()) return bus_heartbeat_topic_;
  if (heartbeat_ && heartbeat_->tripped()) return failsafe_.config().heartbeat_topic;
  return "";
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
    if (!e.channels.empty() && e.action == "safe") {
      failsafe_active_ = text;
      failsafe_active_trigger_ = e.trigger;
    }
  }
  // A device with no fail-safe configured only notes a restart: nothing was written.
  const bool note = e.channels.empty() && e.action == "leave" && !hasSafeStates();
  if (!ros::ok()) {
    // Shutting down: rosconsole is gone, and this is what the user must still see.
    std::fprintf(stderr, "[%s] %s: fail-safe %s\n", e.confirmed ? "WARN" : "ERROR",
                 device_->name().c_str(), text.c_str());
  } else if (note) {
    ROS_INFO("%s: restart detected (%s); on_restart: leave", device_->name().c_str(),
             e.reason.c_str());
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

void DeviceAdapter::externalWrite(const Request& request, CommandSource source) {
  const OutputTargets set = device_->outputsWrittenBy(request);
  if (!set.empty()) failsafe_.commanded(set.channels, set.states, source);
  const std::vector<TimedIntent> timed = device_->timedWrittenBy(request);
  for (const TimedIntent& t : timed) failsafe_.timed(t, source);
  // Any other write (registers the type does not decode) shows at the next poll.
  if (set.empty() && timed.empty() && !isBitFunction(request.function))
    failsafe_.adoptChangesNextPoll(source);
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
  // The heartbeat's state, whatever was written since: a write while it is lost does not bring
  // the controller back.
  const std::string lost = lostHeartbeat();
  if (bus_heartbeat_) status.add("bus heartbeat", bus_heartbeat_->tripped() ? "lost" : "alive");
  if (heartbeat_) status.add("device heartbeat", heartbeat_->tripped() ? "lost" : "alive");
  std::vector<std::string> held;
  for (size_t i = 0; i < names.size(); ++i)
    if (failsafe_.heldBy(static_cast<uint8_t>(i)) != 0) held.push_back(names[i]);
  status.add("held safe until commanded", held.empty() ? "none" : join(held));
  const OutputTargets owed = failsafe_.owed();
  status.add("safe writes owed", owed.empty() ? "none" : channelNames(names, owed.channels));
  std::lock_guard<std::mutex> lock(failsafe_mutex_);
  status.add("restarts detected", restarts_detected_);
  status.add("fail-safe events", failsafe_events_);
  status.add("last fail-safe event", last_failsafe_.empty() ? "none" : last_failsafe_);
  if (!lost.empty()) {
    status.mergeSummary(
        diagnostic_msgs::DiagnosticStatus::WARN,
        "heartbeat lost (no message on " + lost + "): outputs held in their safe state");
  } else if (!failsafe_active_.empty() && failsafe_active_trigger_ != "heartbeat") {
    // After a heartbeat loss the held channels are listed above; the heartbeat is back.
    status.mergeSummary(diagnostic_msgs::DiagnosticStatus::WARN,
                        "outputs in their safe state after " + failsafe_active_);
  }
}

}  // namespace modbus_rtu_driver
