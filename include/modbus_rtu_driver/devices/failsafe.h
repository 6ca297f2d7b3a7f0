// What a device's outputs do when control goes away: the configuration (ROS-free). The
// configuration says, per output channel, which state is safe, and when the fail-safe acts;
// failsafe/channel_intents.h follows what each channel should show.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/core/modbus/types.h"

namespace modbus_rtu_driver {

// kLeave: no safe state, the fail-safe leaves the output alone (YAML `hold`, its word since
// the first release); not ChannelIntents::hold, which keeps a channel in its safe state.
enum class SafeState { kLeave, kOff, kOn };
enum class OnRestart { kLeave, kRestore, kSafe };

inline constexpr NameTable<SafeState, 3> kSafeStateNames{
    {{SafeState::kOff, "off"}, {SafeState::kOn, "on"}, {SafeState::kLeave, "hold"}}};
inline constexpr NameTable<OnRestart, 3> kOnRestartNames{
    {{OnRestart::kRestore, "restore"}, {OnRestart::kSafe, "safe"}, {OnRestart::kLeave, "leave"}}};
// "hold", or on / off in any of the switch words (kSwitchWords: on/off, true/false, yes/no, 1/0).
bool parseSafeState(const std::string& text, SafeState* out);
// The words parseSafeState takes, for an error message.
std::string safeStateWords();
const char* safeStateName(SafeState state);
const char* onRestartName(OnRestart policy);

// Outputs to write: channels[i] to states[i].
struct OutputTargets {
  std::vector<uint8_t> channels;
  std::vector<bool> states;
  bool empty() const { return channels.empty(); }
};

struct FailsafeConfig {
  std::vector<SafeState> safe_state;    // per output channel; empty = every channel holds
  std::vector<double> command_timeout;  // s per output channel; empty or 0 = no dead man
  OnRestart on_restart = OnRestart::kLeave;
  bool on_start_safe = false;      // on_start: safe (true) | keep
  std::string heartbeat_topic;     // this device's own heartbeat; empty = none
  double heartbeat_timeout = 0.0;  // s

  SafeState safeStateOf(size_t channel) const {
    return channel < safe_state.size() ? safe_state[channel] : SafeState::kLeave;
  }
  double commandTimeoutOf(size_t channel) const {
    return channel < command_timeout.size() ? command_timeout[channel] : 0.0;
  }
  bool hasSafeStates() const;
  // The channels (of `channels`) with a safe state other than hold, and that state.
  OutputTargets safeTargets(size_t channels) const;
};

// A timed command on one output channel, as its device type decodes it: `during` from when the
// device confirmed it for `seconds`, then `after` (a flash, a pulse burst, a PWM run with an
// end). No `during`: the device switches the channel by itself meanwhile (a PWM burst), any
// level may show. `seconds` < 0: the device drives the channel with no end the node knows (a
// continuous PWM run).
struct TimedIntent {
  TimedIntent() = default;
  TimedIntent(uint8_t ch, std::optional<bool> level_during, bool level_after, double for_seconds)
      : channel(ch), during(level_during), after(level_after), seconds(for_seconds) {}
  uint8_t channel = 0;
  std::optional<bool> during;
  bool after = false;
  double seconds = -1.0;
  // A continuous run the node can start again after a power cycle stopped it: the write that
  // started it (sent once, never retried; docs/failsafe.md, "What restore writes"). None for a
  // run with an end, or one whose settings the node does not know.
  std::optional<Request> restart;
};

}  // namespace modbus_rtu_driver
