#include "modbus_rtu_driver/failsafe/generic_failsafe.h"

#include <algorithm>

#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/core/modbus/text.h"

namespace modbus_rtu_driver {

GenericFailsafe::GenericFailsafe(GenericDevice& device, BusScheduler& scheduler)
    : device_(device), scheduler_(scheduler) {}

std::future<Result> GenericFailsafe::applySafe(const std::string& trigger,
                                               const std::string& reason) {
  if (!hasSafeValues()) return readyResult(Result::success());
  return scheduler_.submit(device_.name(), [this, trigger, reason](Transport& t) {
    return writeSafe(t, trigger, reason);
  });
}

void GenericFailsafe::afterPoll(const Result& poll) {
  if (!safe_pending_ || noProperAnswer(poll.error)) return;
  safe_pending_ = false;  // one retry queued; it sets this again if it fails too
  scheduler_.submit(device_.name(), [this](Transport& t) {
    return writeSafe(t, "restart",
                     "the device answers again; its safe values were not reached before");
  });
}

void GenericFailsafe::userWriteConfirmed() {
  std::lock_guard<std::mutex> lock(mutex_);
  status_.active.clear();
}

Result GenericFailsafe::writeSafe(Transport& t, const std::string& trigger,
                                  const std::string& reason) {
  FailsafeReport r;
  r.device = device_.name();
  r.trigger = trigger;
  r.reason = reason;
  r.action = "safe";
  for (size_t i : device_.safeSignals()) {
    const double v = *device_.signals()[i].safe_value;
    r.channels.push_back(device_.signals()[i].name);
    r.states.push_back(v != 0.0);
    r.values.push_back(v);
  }
  bool silent = false;
  Result w = device_.writeSafeValues(t, &silent);
  // Not reached because the device did not answer: tried again when it answers. A refusal,
  // or a value read back that differs, is the device's answer: reported, not retried (on
  // every poll it would only repeat the event), and the other signals were still written.
  safe_pending_ = silent;
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
  if (s.type == SignalType::kBool) return s.name + (*s.safe_value != 0 ? " on" : " off");
  return s.name + " " + numberText(*s.safe_value) + (s.unit.empty() ? "" : " " + s.unit);
}

std::string GenericFailsafe::text(const FailsafeReport& r) const {
  const auto& signals = device_.signals();
  std::string t =
      r.trigger + " (" + r.reason + "): " + join(r.channels, ", ", [&](const std::string& name) {
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
