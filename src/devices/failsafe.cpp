#include "modbus_rtu_driver/devices/failsafe.h"

#include <chrono>
#include <map>

namespace modbus_rtu_driver {

bool parseSafeState(const std::string& text, SafeState* out) {
  // YAML 1.1 and rosparam turn a bare on/off into a boolean: its text is true/false.
  const auto state = text == "true"    ? SafeState::kOn
                     : text == "false" ? SafeState::kOff
                                       : valueIn(kSafeStateNames, text);
  if (state) *out = *state;
  return state.has_value();
}

const char* safeStateName(SafeState state) {
  return nameIn(kSafeStateNames, state).data();  // the names are literals: terminated
}

const char* onRestartName(OnRestart policy) {
  return nameIn(kOnRestartNames, policy).data();
}

bool FailsafeConfig::hasSafeStates() const {
  for (SafeState s : safe_state)
    if (s != SafeState::kHold) return true;
  return false;
}

FailsafeTracker::FailsafeTracker(FailsafeConfig config, size_t channels, Clock& clock)
    : config_(std::move(config)),
      channels_(channels),
      clock_(clock),
      confirmed_(channels),
      written_(channels),
      held_safe_(channels, false),
      settled_(channels, true),
      command_deadline_(channels) {}

OutputTargets FailsafeTracker::safeTargets() const {
  OutputTargets t;
  for (size_t i = 0; i < channels_; ++i) {
    const SafeState s = config_.safeStateOf(i);
    if (s == SafeState::kHold) continue;
    t.channels.push_back(static_cast<uint8_t>(i));
    t.states.push_back(s == SafeState::kOn);
  }
  return t;
}

OutputTargets FailsafeTracker::restoreTargets() const {
  std::lock_guard<std::mutex> lock(mutex_);
  OutputTargets t;
  for (size_t i = 0; i < channels_; ++i) {
    const SafeState safe = config_.safeStateOf(i);
    if (held_safe_[i] && safe != SafeState::kHold) {
      t.channels.push_back(static_cast<uint8_t>(i));
      t.states.push_back(safe == SafeState::kOn);
    } else if (written_[i]) {
      t.channels.push_back(static_cast<uint8_t>(i));
      t.states.push_back(*written_[i]);
    }
  }
  return t;
}

OutputTargets FailsafeTracker::afterPollTargets(Verdict verdict) const {
  std::map<uint8_t, bool> by_channel;
  const auto put = [&by_channel](const OutputTargets& t) {
    for (size_t i = 0; i < t.channels.size(); ++i) by_channel[t.channels[i]] = t.states[i];
  };
  if (verdict != Verdict::kNormal && config_.on_restart == OnRestart::kRestore)
    put(restoreTargets());
  if ((verdict != Verdict::kNormal && config_.on_restart == OnRestart::kSafe) || safePending())
    put(safeTargets());
  OutputTargets t;
  for (const auto& [channel, state] : by_channel) {
    t.channels.push_back(channel);
    t.states.push_back(state);
  }
  return t;
}

void FailsafeTracker::confirmed(const std::vector<uint8_t>& channels,
                                const std::vector<bool>& states, Writer writer) {
  std::lock_guard<std::mutex> lock(mutex_);
  write_during_poll_ = true;
  for (size_t i = 0; i < channels.size() && i < states.size(); ++i) {
    const uint8_t ch = channels[i];
    if (ch >= channels_) continue;
    confirmed_[ch] = states[i];
    settled_[ch] = true;
    written_[ch] = states[i];
    if (writer == Writer::kUser) held_safe_[ch] = false;
  }
}

void FailsafeTracker::holdSafe(const std::vector<uint8_t>& channels) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (uint8_t ch : channels)
    if (ch < channels_ && config_.safeStateOf(ch) != SafeState::kHold) held_safe_[ch] = true;
}

bool FailsafeTracker::anyHeldSafe() const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (bool held : held_safe_)
    if (held) return true;
  return false;
}

void FailsafeTracker::release(uint8_t channel) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (channel < channels_) held_safe_[channel] = false;
}

void FailsafeTracker::pollStarting() {
  std::lock_guard<std::mutex> lock(mutex_);
  write_during_poll_ = false;
}

void FailsafeTracker::externalWrite(const OutputTargets& set) {
  std::lock_guard<std::mutex> lock(mutex_);
  external_write_ = true;
  write_during_poll_ = true;
  for (size_t i = 0; i < set.channels.size() && i < set.states.size(); ++i) {
    const uint8_t ch = set.channels[i];
    if (ch >= channels_) continue;
    // Even when the output was already in that state: the client commanded it.
    written_[ch] = set.states[i];
    confirmed_[ch] = set.states[i];
    settled_[ch] = true;
    held_safe_[ch] = false;
    took_external_ = true;
  }
}

void FailsafeTracker::observeWrite(const std::vector<bool>& outputs) {
  std::lock_guard<std::mutex> lock(mutex_);
  write_during_poll_ = true;
  for (size_t i = 0; i < channels_ && i < outputs.size(); ++i) confirmed_[i] = outputs[i];
}

void FailsafeTracker::selfTimed(uint8_t channel) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (channel < channels_) settled_[channel] = false;
  write_during_poll_ = true;
}

FailsafeTracker::Verdict FailsafeTracker::observePoll(const std::vector<bool>& outputs,
                                                      const std::vector<bool>& self_timed,
                                                      bool was_offline,
                                                      std::vector<uint8_t>* changed) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (changed) changed->clear();
  if (write_during_poll_) {
    // What it read may predate that write: neither a restart nor the new confirmed states.
    write_during_poll_ = false;
    return was_offline ? Verdict::kCameBack : Verdict::kNormal;
  }
  const bool adopt = external_write_;  // someone else's confirmed write: not a restart
  external_write_ = false;
  bool differs = false;
  for (size_t i = 0; i < channels_ && i < outputs.size(); ++i) {
    const bool timed = !settled_[i] || (i < self_timed.size() && self_timed[i]);
    if (!timed && confirmed_[i] && *confirmed_[i] != outputs[i]) {
      if (adopt) {
        written_[i] = outputs[i];
        held_safe_[i] = false;
        took_external_ = true;
      } else {
        differs = true;
        if (changed) changed->push_back(static_cast<uint8_t>(i));
      }
    }
    confirmed_[i] = outputs[i];
  }
  if (was_offline) return Verdict::kCameBack;
  return differs ? Verdict::kOutputsChanged : Verdict::kNormal;
}

bool FailsafeTracker::tookExternalWrite() {
  std::lock_guard<std::mutex> lock(mutex_);
  const bool took = took_external_;
  took_external_ = false;
  return took;
}

void FailsafeTracker::commandReceived(uint8_t channel, bool state) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (channel >= channels_) return;
  const double timeout = config_.commandTimeoutOf(channel);
  if (state && timeout > 0) {
    command_deadline_[channel] = clock_.now() + std::chrono::duration_cast<Clock::duration>(
                                                    std::chrono::duration<double>(timeout));
  } else {
    command_deadline_[channel].reset();
  }
}

std::vector<uint8_t> FailsafeTracker::expiredCommands() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<uint8_t> expired;
  const auto now = clock_.now();
  for (size_t i = 0; i < channels_; ++i) {
    if (!command_deadline_[i] || now < *command_deadline_[i]) continue;
    command_deadline_[i].reset();
    expired.push_back(static_cast<uint8_t>(i));
  }
  return expired;
}

void FailsafeTracker::setSafePending(bool pending) {
  std::lock_guard<std::mutex> lock(mutex_);
  safe_pending_ = pending;
}

bool FailsafeTracker::safePending() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return safe_pending_;
}

}  // namespace modbus_rtu_driver
