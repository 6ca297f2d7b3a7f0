// Generic device: one latched topic per signal (published on change), D/signals with every
// signal after each poll, D/<name>/set for writable signals, one poll per rate group.
#include <diagnostic_msgs/DiagnosticStatus.h>
#include <std_msgs/Float64.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>

#include "modbus_rtu_driver/SetValue.h"
#include "modbus_rtu_driver/SignalValues.h"
#include "modbus_rtu_driver/core/bus/rate_meter.h"
#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/devices/generic_device.h"
#include "modbus_rtu_driver/failsafe/generic_failsafe.h"
#include "modbus_rtu_driver/ros/adapter_registry.h"

namespace modbus_rtu_driver {

namespace {

class GenericAdapter : public DeviceAdapter {
 public:
  // The base advertises D/failsafe (latched) in its constructor, before on_start's safe write,
  // so that its event is kept for a late subscriber too.
  using DeviceAdapter::DeviceAdapter;

  void advertise() override {
    const auto& signals = generic().signals();
    published_.assign(signals.size(), std::nullopt);
    warned_.assign(signals.size(), false);
    polled_.assign(generic().groups().size(), false);
    all_pub_ = nh_.advertise<SignalValues>("signals", 50);
    for (size_t i = 0; i < signals.size(); ++i) {
      const SignalConfig& s = signals[i];
      const bool bit = s.type == SignalType::kBool;
      pubs_.push_back(bit ? nh_.advertise<std_msgs::Bool>(s.name, 1, true)
                          : nh_.advertise<std_msgs::Float64>(s.name, 1, true));
      if (!s.writable) continue;
      if (bit)
        services_.push_back(
            nh_.advertiseService<std_srvs::SetBool::Request, std_srvs::SetBool::Response>(
                s.name + "/set",
                [this, i](std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res) {
                  const Result r = write(i, req.data ? 1.0 : 0.0);
                  res.success = r.ok();
                  res.message =
                      answer(r, generic().signals()[i].name + (req.data ? " on" : " off"));
                  return true;
                }));
      else
        services_.push_back(nh_.advertiseService<SetValue::Request, SetValue::Response>(
            s.name + "/set", [this, i](SetValue::Request& req, SetValue::Response& res) {
              const Result r = write(i, req.value);
              res.success = r.ok();
              const SignalConfig& sc = generic().signals()[i];
              std::vector<uint16_t> words;
              generic().encodeWrite(i, req.value, &words);
              const double written =
                  words.empty() ? req.value
                                : sc.toValue(decodeRaw(sc.type, sc.word_order, words.data()));
              // In the signal's unit, both numbers ("set to 1.04 A (written as 1 A)").
              const std::string unit = sc.unit.empty() ? "" : " " + sc.unit;
              std::string what = sc.name + " set to " + numberText(req.value) + unit;
              // Integer registers hold steps of `scale`, float32 has 24 bits: say what it is.
              if (r.ok() &&
                  std::abs(written - req.value) > 1e-9 * std::max(1.0, std::abs(req.value)))
                what += " (written as " + numberText(written) + unit + ")";
              res.message = answer(r, what);
              return true;
            }));
    }
  }

  // The scheduler counts every group's polls under the device's name (a sum of different
  // rates that says nothing): each group's own rates instead.
  void diagnosePollRate(diagnostic_updater::DiagnosticStatusWrapper& status,
                        const DeviceHealth&) override {
    for (size_t g = 0; g < generic().groups().size(); ++g) {
      const auto& group = generic().groups()[g];
      if (group.signals.empty()) continue;
      const std::string key = "poll group " + std::to_string(g);
      status.add(key + " [Hz]", group.rate);
      status.add(key + " achieved [Hz]", rates_[g].rate());
    }
  }

  // Only what a generic device has: no output safe states, no on_restart, no restart count.
  void diagnoseFailsafe(diagnostic_updater::DiagnosticStatusWrapper& status) override {
    const GenericFailsafe& safe = *unit_.genericSafe();
    if (!safe.hasSafeValues()) return;  // no fail-safe at all
    status.add("safe values", join(generic().safeSignals(), ", ",
                                   [&safe](size_t i) { return safe.describeSafeValue(i); }));
    const FailsafeConfig& fs = unit_.failsafe().config();
    status.add("on_start", fs.on_start_safe ? "safe" : "leave");
    if (!fs.heartbeat_topic.empty())
      status.add("device heartbeat",
                 fs.heartbeat_topic + " within " + numberText(fs.heartbeat_timeout) + " s");
    const GenericFailsafe::Status s = safe.status();
    status.add("fail-safe events", s.events);
    status.add("last fail-safe event", s.last_event.empty() ? "none" : s.last_event);
    if (!s.active.empty())
      status.mergeSummary(diagnostic_msgs::DiagnosticStatus::WARN,
                          "signals at their safe values after " + s.active);
  }

  void diagnoseType(diagnostic_updater::DiagnosticStatusWrapper& status) override {
    // Read on the diagnostics thread: the split list only grows, and copies are taken whole.
    std::vector<std::string> splits;
    std::string unread;
    {
      std::lock_guard<std::mutex> lock(splits_mutex_);
      splits = splits_;
      unread = unread_;
    }
    // An exception still counts as an answer (the device is online): say which values lack.
    if (!unread.empty())
      status.mergeSummary(diagnostic_msgs::DiagnosticStatus::WARN, "signals not read: " + unread);
    status.add("signals not read", unread.empty() ? "none" : unread);
    status.add("signals", generic().signals().size());
    status.add("merged reads split (device refused them)", splits.size());
    for (size_t k = 0; k < splits.size(); ++k) status.add("split " + std::to_string(k), splits[k]);
  }

 private:
  GenericDevice& generic() const { return static_cast<GenericDevice&>(*device_); }

  // No outputs (the base's topics stay silent, no restart detection): only the signals. Safe
  // values not reached (the device was silent) are written once it answers again (the unit).
  void onPoll(size_t group, const Result& r) override {
    polled_[group] = true;
    rates_[group].record(std::chrono::steady_clock::now());
    publishSignals(true);
    warnRefusedOnce(group, r);
  }

  // A set, or the safe values written: the signals' topics (not before start(): on_start).
  void onChanged() override {
    if (!pubs_.empty()) publishSignals(false);
  }

  Result write(size_t i, double value) { return unit().writeSignal(i, value).get(); }

  // Bus thread: each signal's topic when its value changed, D/signals after a poll.
  void publishSignals(bool after_poll) {
    const auto& signals = generic().signals();
    const auto& states = generic().states();
    SignalValues all;
    all.header.stamp = ros::Time::now();
    for (size_t i = 0; i < signals.size(); ++i) {
      const SignalState& st = states[i];
      all.names.push_back(signals[i].name);
      all.units.push_back(signals[i].unit);
      all.values.push_back(st.value);
      all.valid.push_back(st.valid);
      std::optional<double>& published = published_[i];
      if (!st.valid || (published && sameReading(*published, st.value))) continue;
      published = st.value;
      if (signals[i].type == SignalType::kBool) {
        std_msgs::Bool m;
        m.data = st.value != 0.0;
        publishLater(pubs_[i], m);
      } else {
        std_msgs::Float64 m;
        m.data = st.value;
        publishLater(pubs_[i], m);
      }
    }
    if (after_poll) publishLater(all_pub_, std::move(all));
    // Signals whose group was polled and whose last read failed.
    std::vector<std::string> unread_names;
    for (size_t g = 0; g < polled_.size(); ++g) {
      if (!polled_[g]) continue;
      for (size_t i : generic().groups()[g].signals)
        if (!states[i].valid) unread_names.push_back(signals[i].name);
    }
    const std::string unread = join(unread_names);
    std::lock_guard<std::mutex> lock(splits_mutex_);
    splits_ = generic().splits();
    unread_ = unread;
  }

  // Bus thread: a signal the device refuses (an exception: it answers, so it is not offline
  // and nothing else says it) is logged once with the exception, and once when read again.
  void warnRefusedOnce(size_t g, const Result& r) {
    const auto& signals = generic().signals();
    for (size_t i : generic().groups()[g].signals) {
      const bool valid = generic().states()[i].valid;
      if (!valid && !warned_[i] && r.error == ErrorKind::kException) {
        ROS_WARN("%s: signal %s cannot be read: %s", device_->name().c_str(),
                 signals[i].name.c_str(), r.message.c_str());
        warned_[i] = true;
      } else if (valid && warned_[i]) {
        ROS_INFO("%s: signal %s is read again", device_->name().c_str(), signals[i].name.c_str());
        warned_[i] = false;
      }
    }
  }

  ros::Publisher all_pub_;
  std::vector<ros::Publisher> pubs_;
  std::vector<ros::ServiceServer> services_;
  std::vector<std::optional<double>> published_;  // bus thread only
  std::vector<bool> polled_;                      // by poll group; bus thread only
  std::vector<bool> warned_;                      // by signal: refused and logged; bus thread
  // By poll group: recorded on the bus thread, read by diagnostics (each locks itself).
  std::vector<RateMeter> rates_ = std::vector<RateMeter>(generic().groups().size());
  std::mutex splits_mutex_;  // the two below: copies for diagnostics
  std::vector<std::string> splits_;
  std::string unread_;
};

}  // namespace

// `type: generic` devices get this adapter (ros/adapter_registry.h).
[[maybe_unused]] const bool kGenericAdapterRegistered =
    adapterClasses().add(kGenericType, makeAdapter<GenericAdapter>);

}  // namespace modbus_rtu_driver
