// What a device's outputs do when control goes away (ROS-free). The configuration says, per
// output channel, which state is safe; FailsafeTracker follows what was commanded and confirmed,
// tells when a poll shows that the device restarted, and runs the dead-man deadlines of command
// topics. The node (ROS side) decides when to write the safe states: shutdown, heartbeat lost,
// command timeout, device restart, start-up.
#pragma once

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/core/modbus/text.h"

namespace modbus_rtu_driver {

enum class SafeState { kHold, kOff, kOn };
enum class OnRestart { kLeave, kRestore, kSafe };

inline constexpr NameTable<SafeState, 3> kSafeStateNames{
    {{SafeState::kOff, "off"}, {SafeState::kOn, "on"}, {SafeState::kHold, "hold"}}};
inline constexpr NameTable<OnRestart, 3> kOnRestartNames{
    {{OnRestart::kRestore, "restore"}, {OnRestart::kSafe, "safe"}, {OnRestart::kLeave, "leave"}}};
// "off", "on", "hold"; also true/false, which is what rosparam makes of a bare on/off.
bool parseSafeState(const std::string& text, SafeState* out);
const char* safeStateName(SafeState state);
const char* onRestartName(OnRestart policy);

struct FailsafeConfig {
  std::vector<SafeState> safe_state;    // per output channel; empty = every channel holds
  std::vector<double> command_timeout;  // s per output channel; empty or 0 = no dead man
  OnRestart on_restart = OnRestart::kLeave;
  bool on_start_safe = false;      // on_start: safe (true) | keep
  std::string heartbeat_topic;     // this device's own heartbeat; empty = none
  double heartbeat_timeout = 0.0;  // s

  SafeState safeStateOf(size_t channel) const {
    return channel < safe_state.size() ? safe_state[channel] : SafeState::kHold;
  }
  double commandTimeoutOf(size_t channel) const {
    return channel < command_timeout.size() ? command_timeout[channel] : 0.0;
  }
  bool hasSafeStates() const;
};

// Outputs to write: channels[i] to states[i].
struct OutputTargets {
  std::vector<uint8_t> channels;
  std::vector<bool> states;
  bool empty() const { return channels.empty(); }
};

// Per device; any thread (it locks).
class FailsafeTracker {
 public:
  enum class Verdict { kNormal, kCameBack, kOutputsChanged };

  FailsafeTracker(FailsafeConfig config, size_t channels, Clock& clock = Clock::steady());

  const FailsafeConfig& config() const { return config_; }
  // Channels with a safe state other than hold, and that state.
  OutputTargets safeTargets() const;
  // What a restore writes again: per channel, the last state the node confirmed by a write of
  // its own (a user's command, a safe write, a restore) or saw a share client or raw write set;
  // a channel a trigger holds safe (holdSafe) gets its safe state instead. Channels never
  // written are left out.
  OutputTargets restoreTargets() const;
  // What to write after a poll: on a restart (verdict other than kNormal), on_restart's targets;
  // and a safe write not done yet (safePending) is done now, its states written over a
  // restore's (the restore of the other channels is not skipped for it).
  OutputTargets afterPollTargets(Verdict verdict) const;

  // Who made a confirmed write: a user's command (service, command topic) is a new command and
  // ends a hold; the fail-safe's own writes and restores do not.
  enum class Writer { kUser, kFailsafe };
  // Bus thread, right after the device confirmed a write.
  void confirmed(const std::vector<uint8_t>& channels, const std::vector<bool>& states,
                 Writer writer);
  // A trigger that lasts (heartbeat lost, command timeout) holds these channels in their safe
  // state, whether or not the safe write got through, until a user commands them again.
  void holdSafe(const std::vector<uint8_t>& channels);
  bool anyHeldSafe() const;
  // A user's timed command (a pulse, a PWM run) on `channel` was confirmed: it ends the hold.
  void release(uint8_t channel);
  // Bus thread: a write the node carried for someone else (a share client, a raw write) was
  // confirmed by the device's reply. `set`: the outputs it set (a restore writes them again;
  // they end a hold as a user's command does). The next poll takes any other change it reads
  // as written by a user too (a flash through registers), not as a restart.
  void externalWrite(const OutputTargets& set);
  // Whether the last poll took such a write's changes as commanded (asked once).
  bool tookExternalWrite();
  // Bus thread, after any write job (confirmed or not): the device's snapshot, read back where a
  // reply was lost, is what the next poll is compared with.
  void observeWrite(const std::vector<bool>& outputs);
  // The device may change `channel` by itself from now on (a PWM run, a timed flash): polls
  // are not compared on it until a plain write settles it again.
  void selfTimed(uint8_t channel);

  // Bus thread, as a poll job starts. Writes and shared requests run between a poll's
  // transactions (BusScheduler::PollTransport), so the outputs it read may predate one of them:
  // such a poll is not compared (no restart is seen in it); the next one is.
  void pollStarting();

  // Bus thread, after a successful poll. `self_timed[i]`: the device reports channel i as
  // timed by itself right now. `was_offline`: the device had been offline before this poll.
  // kCameBack / kOutputsChanged (with `changed` filled) mean it restarted; the new states are
  // taken as the confirmed ones either way.
  Verdict observePoll(const std::vector<bool>& outputs, const std::vector<bool>& self_timed,
                      bool was_offline, std::vector<uint8_t>* changed);

  // Command topics' dead man: a command that turns a channel with a command_timeout on starts
  // its deadline, any command on it renews or (off) ends it.
  void commandReceived(uint8_t channel, bool state);
  // Channels whose deadline has passed, each returned once.
  std::vector<uint8_t> expiredCommands();

  // A safe write that could not be done (device offline): done when the device answers again.
  void setSafePending(bool pending);
  bool safePending() const;

 private:
  FailsafeConfig config_;
  size_t channels_;
  Clock& clock_;
  mutable std::mutex mutex_;
  std::vector<std::optional<bool>> confirmed_;  // last known state per channel
  std::vector<std::optional<bool>> written_;    // last state a write set, per channel
  std::vector<bool> held_safe_;                 // a lasting trigger holds it safe
  std::vector<bool> settled_;                   // compared on polls
  std::vector<std::optional<Clock::time_point>> command_deadline_;
  bool safe_pending_ = false;
  bool external_write_ = false;     // adopt the next poll's outputs as written
  bool took_external_ = false;      // the last poll did
  bool write_during_poll_ = false;  // a write ran between the running poll's transactions
};

}  // namespace modbus_rtu_driver
