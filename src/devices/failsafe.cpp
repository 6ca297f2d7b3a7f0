#include "modbus_rtu_driver/devices/failsafe.h"

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

OutputTargets FailsafeConfig::safeTargets(size_t channels) const {
  OutputTargets t;
  for (size_t i = 0; i < channels; ++i) {
    const SafeState s = safeStateOf(i);
    if (s == SafeState::kHold) continue;
    t.channels.push_back(static_cast<uint8_t>(i));
    t.states.push_back(s == SafeState::kOn);
  }
  return t;
}

}  // namespace modbus_rtu_driver
