#include "modbus_rtu_driver/devices/failsafe.h"

#include "modbus_rtu_driver/core/modbus/switch_words.h"

namespace modbus_rtu_driver {

bool parseSafeState(const std::string& text, SafeState* out) {
  // on and off in any of the switch words (rosparam turns a bare on/off/yes/no into a boolean,
  // which reaches the node as true/false), or hold.
  if (const auto on = parseSwitch(text)) {
    *out = *on ? SafeState::kOn : SafeState::kOff;
    return true;
  }
  const auto state = valueIn(kSafeStateNames, text);
  if (state) *out = *state;
  return state.has_value();
}

std::string safeStateWords() {
  return "on, off, hold (on/off also as " + std::string(kSwitchWords.substr(8)) + ")";
}

const char* safeStateName(SafeState state) {
  return nameIn(kSafeStateNames, state).data();  // the names are literals: terminated
}

const char* onRestartName(OnRestart policy) {
  return nameIn(kOnRestartNames, policy).data();
}

bool FailsafeConfig::hasSafeStates() const {
  for (SafeState s : safe_state)
    if (s != SafeState::kLeave) return true;
  return false;
}

OutputTargets FailsafeConfig::safeTargets(size_t channels) const {
  OutputTargets t;
  for (size_t i = 0; i < channels; ++i) {
    const SafeState s = safeStateOf(i);
    if (s == SafeState::kLeave) continue;
    t.channels.push_back(static_cast<uint8_t>(i));
    t.states.push_back(s == SafeState::kOn);
  }
  return t;
}

}  // namespace modbus_rtu_driver
