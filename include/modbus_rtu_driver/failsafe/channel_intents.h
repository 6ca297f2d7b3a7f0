// What each output channel of one device should show, and why (ROS-free): the newest command
// the device confirmed on it and where it came from, timed commands with their end and final
// level, which triggers hold it safe, and the safe writes still owed to it. One question,
// expected(channel, t), serves both the writes after a restart (restore) and the question whether
// a changed output is a restart, a timed command ending or a PWM toggling. docs/failsafe.md is
// the spec ("One intent per channel").
//
// Thread safety: every method locks; the bus thread reports confirmed writes and polls, the
// timers report triggers and commands.
#pragma once

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/devices/failsafe.h"
#include "modbus_rtu_driver/failsafe/failsafe_event.h"

namespace modbus_rtu_driver {

// Who gave a channel its newest intent.
enum class CommandSource {
  kFound,    // the state the node found at its start (first good poll), or adopted from a poll
  kUser,     // a service or command topic (C/set, C/command, set_outputs)
  kShare,    // a share client's write, decoded per device type
  kRaw,      // write_coils / write_registers
  kTimed,    // pulse / flash / PWM run started by a service
  kRestore,  // on_restart: restore wrote it
  kSafe,     // a safe write (a trigger, on_restart: safe)
};
const char* commandSourceName(CommandSource source);

// Triggers that hold channels in their safe state until they are commanded again.

// What a poll at time t may show on a channel.
struct Expectation {
  enum class Kind { kAny, kLevel, kEither } kind = Kind::kAny;
  bool level = false;  // kLevel: the level; kEither: the level it settles on (a timed end)
};

class ChannelIntents {
 public:
  // How near a timed command's end a poll may show either level: the device's timer starts
  // when the frame arrives, the node's when the reply does, and polls come between.
  static constexpr double kEndSlackSeconds = 0.5;
  static constexpr double kEndSlackFraction = 0.02;

  ChannelIntents(FailsafeConfig config, size_t channels, Clock& clock = Clock::steady());

  const FailsafeConfig& config() const { return config_; }
  size_t channels() const { return channels_; }
  // Channels with a safe state other than hold, and that state.
  OutputTargets safeTargets() const;

  // --- confirmed writes (bus thread, right after the device confirmed them) ---
  // Plain levels. A user's, share client's or raw write ends every hold on those channels and
  // drops a safe write still owed to them; a restore or safe write does neither of the first
  // (it is the fail-safe's own) but pays what it owed.
  void commanded(const std::vector<uint8_t>& channels, const std::vector<bool>& levels,
                 CommandSource source);
  // A timed command (flash, pulse burst, PWM run): ends holds, drops owed writes.
  void timed(const TimedIntent& intent, CommandSource source);
  // A write whose effect on `channel` the node cannot decode (a PWM stopped): the next poll's
  // level is taken as commanded (a running PWM there: the device's). With `not_before_s`, polls
  // before then are not compared and do not count (a timed command whose answer was lost may
  // run until its end).
  void adoptNextPoll(uint8_t channel, CommandSource source, double not_before_s = 0);
  // A stop of the channel's timed command (a PWM run) that the device confirmed: the run no
  // longer drives the output, so the next poll's level is taken as commanded by `source`, with
  // no wait for the run's planned end (adoptNextPoll waits for it: a write whose answer was
  // lost may not have stopped it).
  void stoppedNextPoll(uint8_t channel, CommandSource source);
  // A client's confirmed register write that the type decodes as touching `channel` only (an
  // LD58A08 PWM stop): the next poll's level is the intent; if it differs from what the channel
  // should have shown, it is the client's command (it ends a hold from before the write).
  void adoptChangeNextPoll(uint8_t channel, CommandSource source);
  // A confirmed write the node cannot decode per channel (a share client's or raw register
  // write): the next compared poll takes every channel that differs as commanded by `source`,
  // not as a restart.
  void adoptChangesNextPoll(CommandSource source);
  // A write that may have changed outputs ran (confirmed or not): the running poll's reads may
  // predate it, so that poll is not compared.
  void writeRan();

  // --- triggers (any thread) ---
  // A lasting trigger (heartbeat lost, command timeout) fired at `at`: the channels (all with a
  // safe state when `channels` is empty) are held safe until commanded again.
  // `trigger`: one that holds (holdsChannels).
  void hold(const std::vector<uint8_t>& channels, Trigger trigger);
  // Channels held safe now, and their states: what a heartbeat's or dead man's write writes
  // when the bus gets to it (a channel commanded since the trigger is no longer held).
  OutputTargets heldTargets(const std::vector<uint8_t>& only) const;
  bool anyHeld() const;
  bool held(uint8_t channel) const;
  bool heldBy(uint8_t channel, Trigger trigger) const;
  // Held channels whose safe write was confirmed that the last compared poll showed not in
  // their safe state (a power cycle, a command whose answer was lost, a PWM someone started):
  // the hold puts them back, whatever on_restart says.
  std::vector<uint8_t> heldNotSafe() const;

  // A safe write (trigger time `since`) that did not get through: owed per channel, written when
  // the device answers again, unless the channel is commanded after `since`.
  void owe(const OutputTargets& targets, Clock::time_point since);
  OutputTargets owed() const;

  // --- polls (bus thread) ---
  enum class Verdict { kNormal, kCameBack, kOutputsChanged };
  // A poll starts: returns the channels whose deciding read is due (a command whose answer was
  // lost, past its end plus the slack), which the device should read first (an LD58A08 reads
  // one channel's PWM registers per poll).
  std::vector<uint8_t> pollStarting();
  // `self_timed[i]`: the device reports channel i as driven by itself now (a running PWM);
  // `read_now[i]`: this poll read that (empty: every channel), not an older snapshot.
  // A channel with no intent yet takes the level found as its intent (kFound).
  Verdict observePoll(const std::vector<bool>& outputs, const std::vector<bool>& self_timed,
                      bool was_offline, std::vector<uint8_t>* changed,
                      const std::vector<bool>& read_now = {});
  // The PWM runs the device reports now, read just before a restore (`runs[i]`: channel i):
  // each that is no timed command of the node's still running makes its channel the device's,
  // as a poll that reads it does.
  void observeRuns(const std::vector<bool>& runs);
  // The runs a poll read before a later read of it failed (F37: read at a poll): the same, on
  // the channels not commanded since that poll started.
  void observeRunsOfFailedPoll(const std::vector<bool>& runs);
  // Whether the last poll adopted a write the node carried for someone else (asked once).
  bool tookAdoptedWrite();

  // What a poll at `t` may show on `channel` (docs/failsafe.md, "What the board should show").
  Expectation expected(uint8_t channel, Clock::time_point t) const;
  // Per channel: a timed command of the node's (or one whose answer was lost) may still drive
  // it now, up to its end plus the slack. A read back cannot confirm a plain write there whose
  // answer was lost: the write would end the run, and the level may be the run's.
  std::vector<bool> timedMayRun() const;
  // What to write after a poll with `verdict`, computed when the write runs (so a command
  // confirmed in between is not undone): on a restart, on_restart's targets (restore: every
  // channel's expected level; safe: the safe states); and every owed safe write, over them.
  // `device_runs[i]`: the device reports a PWM running on channel i, read just before the
  // write (a restore does not write such a channel: it is the device's).
  OutputTargets afterPollTargets(Verdict verdict, const std::vector<bool>& device_runs = {}) const;
  // The continuous runs a restore after `verdict` starts again (on_restart: restore): the
  // node's own (TimedIntent::restart) that `device_runs`, read just before, shows stopped, on
  // channels neither held nor owed (docs/failsafe.md, "What restore writes").
  std::vector<TimedIntent> runsToStartAgain(Verdict verdict,
                                            const std::vector<bool>& device_runs) const;

  // --- timed commands across a node's restart ---
  // The timed commands not ended at `now`, with the seconds left (< 0: no end), for the next
  // node to resume if this one is killed (a flash's end is then not taken for a restart).
  std::vector<TimedIntent> runningTimed() const;
  // Channels left unknown by a write whose outcome is unknown (adoptNextPoll) while a run the
  // device drives went on there: a run with an end not ended yet, or (`driven_too`) one with no
  // end. A coil write does not stop such a run on a device that keeps runs (the LD58A08), so it
  // still goes on whatever the write did (DeviceFailsafe::runsKeptOverCoilWrites).
  std::vector<bool> runsUnderAdoption(bool driven_too) const;
  // A timed command whose answer was lost: its channel is adopted at the first poll after its
  // end plus the slack (`not_before_s`), and the run it may have started counts until its end
  // plus the slack (a continuous one, `seconds` < 0, for good): docs/failsafe.md F31, F46.
  void adoptRunNextPoll(uint8_t channel, CommandSource source, double seconds, double not_before_s);
  // The channels where such a run may go on (adoptRunNextPoll): a read of the channel that shows
  // no run ends it too (F31), which only the device's snapshot knows
  // (DeviceFailsafe::runsKeptOverCoilWrites).
  std::vector<bool> lostRunsUnderAdoption() const;
  // Resumes a previous node's timed commands (before the first poll): compared like its own.
  void resumeTimed(const std::vector<TimedIntent>& running);

  // --- the dead man of command topics (any thread) ---
  void commandReceived(uint8_t channel, bool state);
  std::vector<uint8_t> expiredCommands();

  Clock& clock() const { return clock_; }

 private:
  struct Intent {
    CommandSource source = CommandSource::kFound;
    Clock::time_point at{};
    bool level = false;                     // steady level; after `ends` for a timed one
    std::optional<bool> during;             // a timed command's level until `ends` (none: any)
    std::optional<Clock::time_point> ends;  // a timed command's end
    bool driven = false;                    // the device drives it with no known end
    std::optional<Request> restart;         // driven: the node's continuous run, its write
    bool adopt = false;                     // the next poll's level is the intent
    std::optional<Clock::time_point> adopt_from;  // adopt: not before then
    std::optional<bool> adopt_prev;               // adoptChangeNextPoll: the level expected before
    bool adopt_change = false;  // adoptChangeNextPoll: a change is the source's command
    // adopt: the run that went on when the write went out (runsUnderAdoption).
    std::optional<Clock::time_point> run_ends;
    bool run_driven = false;
    // adopt: a run a PWM write whose answer was lost may have started (adoptRunNextPoll), until
    // then (its end plus the slack), or with no end.
    std::optional<Clock::time_point> lost_run_ends;
    bool lost_run_driven = false;
  };
  struct Owed {
    bool level = false;
    Clock::time_point since{};
  };
  bool userSource(CommandSource source) const;
  void newCommand(uint8_t channel, CommandSource source);
  Intent adoptingIntent(uint8_t channel, CommandSource source, Clock::time_point now) const;
  // adoptNextPoll under the lock held: the new intent (nullptr for a channel out of range).
  Intent* adoptNextPollLocked(uint8_t channel, CommandSource source, double not_before_s);
  Expectation expectedLocked(uint8_t channel, Clock::time_point t) const;
  // How near the end of a timed command given at `at` and ending at `ends` either level may show
  // (docs/failsafe.md).
  static Clock::duration endSlack(Clock::time_point at, Clock::time_point ends);
  // The device runs a PWM on the channel (as read now): the channel is the device's unless a
  // timed command of the node's still runs there.
  void deviceRunsLocked(uint8_t channel, Clock::time_point now);

  FailsafeConfig config_;
  size_t channels_;
  Clock& clock_;
  mutable std::mutex mutex_;
  // What is known of one output channel, in one place.
  struct Channel {
    std::optional<Intent> intent;  // what it should show (none: not known)
    uint8_t held = 0;              // bits: 1 << Trigger, for each trigger holding it safe
    Clock::time_point held_since{};
    bool held_written = false;   // a safe write confirmed since the hold began
    bool held_not_safe = false;  // the last compared poll showed it otherwise
    std::optional<Owed> owed;    // a safe write that did not get through, still owed
    std::optional<Clock::time_point> command_deadline;  // command_timeout's (the dead man's)
  };
  std::vector<Channel> ch_;
  bool write_during_poll_ = false;
  Clock::time_point poll_started_at_{};  // the outputs a poll reads were read since then
  bool took_adopted_ = false;
  std::optional<CommandSource> adopt_changes_;  // adoptChangesNextPoll
};

}  // namespace modbus_rtu_driver
