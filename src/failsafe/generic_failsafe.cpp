#include "modbus_rtu_driver/failsafe/generic_failsafe.h"

#include <algorithm>

#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/core/modbus/text.h"

namespace modbus_rtu_driver {

GenericFailsafe::GenericFailsafe(GenericDevice& device, BusScheduler& scheduler)
    : device_(device),
      scheduler_(scheduler),
      set_at_(device.signals().size(), 0),
      owed_since_(device.signals().size(), 0) {}

std::future<Result> GenericFailsafe::applySafe(Trigger trigger, const std::string& reason) {
  if (!hasSafeValues()) return readyResult(Result::success());
  const uint64_t fired = ++sequence_;
  return scheduler_.submit(device_.name(), [this, trigger, reason, fired](Transport& t) {
    return writeSafe(t, trigger, reason, fired, device_.safeSignals());
  });
}

void GenericFailsafe::afterPoll(const Result& poll) {
  if (noProperAnswer(poll.error)) return;
  // The owed signals, each with its own trigger, in one write (a signal set since its own
  // trigger is dropped here, and again in the job for a set that comes before it runs).
  std::vector<size_t> owed;
  for (size_t i = 0; i < owed_since_.size(); ++i) {
    if (owed_since_[i] == 0) continue;
    if (set_at_[i] > owed_since_[i]) {
      owed_since_[i] = 0;  // set since: the newest wins
      continue;
    }
    owed.push_back(i);
  }
  if (owed.empty()) return;
  // One retry queued; writeSafe owes them again if it fails too.
  std::vector<uint64_t> since(owed.size());
  for (size_t k = 0; k < owed.size(); ++k) {
    since[k] = owed_since_[owed[k]];
    owed_since_[owed[k]] = 0;
  }
  scheduler_.submit(device_.name(), [this, owed, since](Transport& t) {
    // Each signal against its own trigger: drop the ones set since.
    std::vector<size_t> still;
    for (size_t k = 0; k < owed.size(); ++k)
      if (set_at_[owed[k]] < since[k]) still.push_back(owed[k]);
    const uint64_t fired = *std::max_element(since.begin(), since.end());
    return writeSafe(t, Trigger::kRestart,
                     "the device answers again; its safe values were not reached before", fired,
                     still);
  });
}

Result GenericFailsafe::write(Transport& t, size_t signal, double value) {
  Result r = device_.writeSignal(t, signal, value);
  if (!r.ok()) return r;
  set_at_[signal] = ++sequence_;
  std::lock_guard<std::mutex> lock(mutex_);
  status_.active.clear();  // no longer "at their safe values"
  return r;
}

Result GenericFailsafe::writeSafe(Transport& t, Trigger trigger, const std::string& reason,
                                  uint64_t fired, const std::vector<size_t>& signals) {
  // A signal the user set since the trigger fired keeps its newer value (also one set between
  // the trigger and this job).
  std::vector<size_t> due;
  for (size_t i : signals)
    if (set_at_[i] < fired) due.push_back(i);
  if (due.empty()) return Result::success();
  FailsafeReport r;
  r.device = device_.name();
  r.trigger = trigger;
  r.reason = reason;
  r.action = Action::kSafe;
  for (size_t i : due) {
    const double v = device_.signals()[i].safe_value.value_or(0.0);  // set: a safe signal
    r.channels.push_back(device_.signals()[i].name);
    r.states.push_back(v != 0.0);
    r.values.push_back(v);
  }
  std::vector<size_t> not_reached;
  Result w = device_.writeSafeValues(t, due, &not_reached);
  // Not reached because the device did not answer: owed, written when it answers. A refusal,
  // or a value read back that differs, is the device's answer: reported, not retried (on
  // every poll it would only repeat the event), and the other signals were still written.
  for (size_t i : due)
    owed_since_[i] = std::find(not_reached.begin(), not_reached.end(), i) != not_reached.end()
                         ? std::max(owed_since_[i], fired)
                         : 0;
  if (written_) written_();
  r.confirmed = r.levels_confirmed = w.ok();
  r.message = w.ok() ? "confirmed by reading the signals back" : w.message;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++status_.events;
    status_.last_event = status_.active = text(r);
  }
  if (sink_) sink_(r);
  return w;
}

std::string GenericFailsafe::describeSafeValue(size_t i) const {
  const SignalConfig& s = device_.signals()[i];
  if (!s.safe_value) return s.name;
  if (s.type == SignalType::kBool) return s.name + (*s.safe_value != 0 ? " on" : " off");
  return s.name + " " + numberText(*s.safe_value) + (s.unit.empty() ? "" : " " + s.unit);
}

std::string GenericFailsafe::text(const FailsafeReport& r) const {
  const auto& signals = device_.signals();
  std::string t = std::string(triggerName(r.trigger)) + " (" + r.reason +
                  "): " + join(r.channels, ", ", [&](const std::string& name) {
                    const auto i = static_cast<size_t>(
                        std::find_if(signals.begin(), signals.end(),
                                     [&](const SignalConfig& s) { return s.name == name; }) -
                        signals.begin());
                    return i < signals.size() ? describeSafeValue(i) : name;
                  });
  if (!r.confirmed) t += "; NOT confirmed: " + r.message;
  return t;
}

GenericFailsafe::Status GenericFailsafe::status() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return status_;
}

}  // namespace modbus_rtu_driver
