// One device's fail-safe, ROS-free: it decides when and what to write (safe states, restores,
// owed safe writes), writes through the bus thread and confirms by reading back, and reports
// what it did. The ROS adapter only turns messages into calls (a command, a heartbeat, a share
// client's write) and publishes the reports. docs/failsafe.md is the spec.
//
// Threads: the trigger calls (applySafe, checkDeadlines, commandReceived) come from any thread;
// the calls marked "bus thread" run in bus jobs or poll callbacks (BusScheduler).
#pragma once

#include <cstdint>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/core/bus/watchdog.h"
#include "modbus_rtu_driver/core/link/until_silent_transport.h"
#include "modbus_rtu_driver/devices/device.h"
#include "modbus_rtu_driver/devices/self_timed_outputs.h"
#include "modbus_rtu_driver/failsafe/channel_intents.h"
#include "modbus_rtu_driver/failsafe/failsafe_event.h"
#include "modbus_rtu_driver/failsafe/kept_timed_commands.h"

namespace modbus_rtu_driver {

// What the fail-safe did, as ~failsafe publishes it (ROS-free).
struct FailsafeReport {
  std::string device;
  Trigger trigger = Trigger::kRestart;
  Action action = Action::kSafe;
  std::string reason, message;
  std::vector<std::string> channels;
  std::vector<bool> states;
  // Per channel: a continuous PWM run a restore started again (its state then says on); and
  // why one of them was not confirmed ("" when all were).
  std::vector<bool> runs;
  // A generic device's report (failsafe/generic_failsafe.h): its channels are signals, and
  // these their safe values (states: value != 0).
  std::vector<double> values;
  std::string runs_failed;
  // The plain levels (runs[i] false) were confirmed; `confirmed` needs the runs too.
  bool levels_confirmed = false;
  bool confirmed = false;
  // A restart on a device with no fail-safe: nothing was written, only noted (log INFO).
  bool note_only = false;
  // "trigger (reason): pump off, lamp on[; NOT confirmed: why]"
  std::string text() const;
  // "PWM run started again on fan, heater" (the channels whose runs[i] is true)
  std::string runsStartedText() const;
};

// The fail-safe's side of a device's /diagnostics.
struct FailsafeStatus {
  std::string safe_states;     // "pump off, lamp on" or "none (every output holds)"
  std::string on_restart;      // restore | safe | leave
  std::string lost_heartbeat;  // the topic of a heartbeat lost now, or ""
  std::optional<bool> bus_heartbeat_lost, device_heartbeat_lost;  // none: not configured
  std::string held;  // channels held safe until commanded, or "none"
  std::string owed;  // channels with a safe write owed, or "none"
  uint64_t restarts_detected = 0, events = 0;
  std::string last_event;  // the newest report in words, or "none"
  std::string warn;        // the WARN summary it asks for, or ""
};

class DeviceFailsafe {
 public:
  using ReportSink = std::function<void(const FailsafeReport&)>;

  DeviceFailsafe(Device& device, BusScheduler& scheduler, Clock& clock = Clock::steady());
  DeviceFailsafe(const DeviceFailsafe&) = delete;
  DeviceFailsafe& operator=(const DeviceFailsafe&) = delete;

  // Where reports go, and what to run when a write of its own changed the outputs (the
  // adapter publishes them); before the bus runs.
  void setReportSink(ReportSink sink) { sink_ = std::move(sink); }
  void setOutputsWritten(std::function<void()> written) { outputs_written_ = std::move(written); }
  // The timed commands running now (flashes, bursts, PWM runs; seconds left), each time that
  // changes: the ROS layer keeps them for the next node's start, so that a node killed during a
  // flash does not take its end for a restart (issue #32 item 6). Looked at after every
  // command's outcome and every poll: one that ended, or that a poll or a write whose answer
  // was lost made unknown, is no longer running, so the next node does not resume it.
  void setTimedChanged(std::function<void(const std::vector<TimedIntent>&)> changed) {
    timed_changed_ = std::move(changed);
  }
  // A previous node's timed commands (seconds left), before the first poll.
  // The previous node's timed commands, still running: they are what is kept now, so that one
  // dropped later (ended, or replaced by a write whose answer was lost) is told.
  void resumeTimed(const std::vector<TimedIntent>& running);
  // The bus-wide heartbeat (none: nullptr), for the status.
  void setBusHeartbeat(const Watchdog* heartbeat, std::string topic);

  const FailsafeConfig& config() const { return intents_.config(); }
  ChannelIntents& intents() { return intents_; }
  Watchdog* heartbeat() { return heartbeat_.get(); }  // this device's own, or nullptr
  bool hasSafeStates() const { return config().hasSafeStates(); }

  // --- triggers (any thread) ---
  // Puts the channels with a safe state there (only those in `only`, when given), confirmed by
  // reading back, and reports it. `trigger`: heartbeat and command_timeout hold the channels
  // safe until commanded again; start and shutdown do not. The future holds the outcome (a
  // ready success when there is nothing to write).
  std::future<Result> applySafe(Trigger trigger, const std::string& reason,
                                const std::vector<uint8_t>& only = {});
  // A trigger that fired: what applySafe takes.
  struct Fired {
    Trigger trigger;
    std::string reason;
    std::vector<uint8_t> only;
  };
  // Command deadlines that passed, and this device's own heartbeat (each returned once).
  std::vector<Fired> firedTriggers();
  // applySafe for each of firedTriggers().
  void checkDeadlines();
  // A command topic's message on `channel` (the dead man's deadline).
  void commandReceived(uint8_t channel, bool state) { intents_.commandReceived(channel, state); }

  // --- the bus thread ---
  // A poll of the device starts: it reads first what the fail-safe waits for.
  void pollStarting() {
    const std::vector<uint8_t> first = intents_.pollStarting();  // always: it notes the start
    if (timed_) timed_->readSelfTimedFirst(first);
  }
  // After a good poll: restart detection, then on_restart's write and the owed safe writes.
  void afterPoll();
  // A poll failed: a PWM run it read before the read that failed is still the device's report
  // (docs/failsafe.md F37).
  void afterFailedPoll();
  // A user's output write is about to be sent / was confirmed / was not confirmed.
  void userWriteSending() { intents_.writeRan(); }
  // The channels a timed command may still drive (ChannelIntents::timedMayRun), for a write's
  // read back.
  std::vector<bool> timedMayRun() const { return intents_.timedMayRun(); }
  void userWriteConfirmed(const std::vector<uint8_t>& channels, const std::vector<bool>& states);
  // A user's write that failed: `changed`, the channels the device confirmed changing before
  // it failed, and every channel when it may have acted (its answer lost, or the port failed
  // after it may have gone out), are taken as found at the next poll.
  void userWriteNotConfirmed(const std::vector<uint8_t>& channels, const Result& result,
                             const std::vector<uint8_t>& changed = {});
  // Around a timed command (flash, pulse, PWM run), and a PWM run stopped.
  void timedCommandSending() { intents_.writeRan(); }
  void timedCommandDone(const TimedIntent& intent, const Result& result);
  // stop_pwm's outcome: confirmed, the next poll gives the level as commanded; its answer lost
  // (the device may have stopped it), the channel is unknown until a poll reads it again.
  void timedCommandStopped(uint8_t channel, const Result& result);
  // Bus thread: a write the node carried for someone else (a share client, a raw write) went
  // out. Confirmed: a command. Its answer lost (or the port dropped mid-frame: the device may
  // have acted): the channels it decodes to are unknown until the next poll, whose level is
  // taken as found (a timed command's: after its end), as for a caller's command
  // (docs/failsafe.md line 94). Refused or unsent: nothing changed. A broadcast (unit 0) is
  // never confirmed: sent, it is as a write whose answer was lost.
  void externalWrite(const Request& request, const Result& result, CommandSource source);

  FailsafeStatus status() const;

 private:
  // A timed command whose answer was lost: its channel unknown until its end plus the slack.
  void adoptAfterLost(const TimedIntent& intent);
  void externalWriteConfirmed(const Request& request, CommandSource source);
  void externalWriteLost(const Request& request);
  // Per channel: a run a coil write there would leave running (the LD58A08 keeps its PWM over
  // a coil write): as the node last read it, or a timed command of the node's before its end.
  std::vector<bool> runsKeptOverCoilWrites() const;
  // Writes `targets`, reads back, reports. `owe_since`: the write carries a trigger's safe
  // states (fired then), owed per channel when it does not get through. `until_silent`: a
  // lasting trigger's write goes through it (`t`; `held_only` is its channel filter): when it
  // refused the read back (no reply to the write), the read and the report come from a job
  // queued behind the other writes, for the channels still held then. `runs_started`: a
  // restore's runs started again just before (startRunsAgain), named in the same report.
  Result writeAndReport(Transport& t, const OutputTargets& targets, Trigger trigger,
                        const std::string& reason, Action action,
                        std::optional<Clock::time_point> owe_since,
                        const UntilSilentTransport* until_silent = nullptr,
                        const std::vector<uint8_t>& held_only = {},
                        const FailsafeReport* runs_started = nullptr);
  // Starts a restore's continuous runs again (ChannelIntents::runsToStartAgain) and names them in
  // `r` (channels, states, runs; runs_failed): the restore's report carries them. The first
  // failure, else success (none to start included).
  Result startRunsAgain(Transport& t, const std::vector<TimedIntent>& runs, FailsafeReport* r);
  // The report's channels and states: `targets`, by the outputs' names.
  void nameTargets(const OutputTargets& targets, FailsafeReport* r) const;
  // Reads the outputs (a poll of the device) and checks `targets` there: success, or why not
  // (`answered`: the read itself got through).
  Result readBack(Transport& t, const OutputTargets& targets, bool* answered = nullptr);
  // After a write and its read back (`w`): takes it as commanded, or owes it (`owe_since`), and
  // reports `r` with the outcome.
  Result settle(const OutputTargets& targets, Result w, FailsafeReport r,
                std::optional<Clock::time_point> owe_since,
                const std::string& confirmed_text = "confirmed by reading the outputs back");
  void report(const FailsafeReport& r);
  void endSafeState();       // a user's confirmed command: no longer "in their safe state"
  void timedMaybeChanged();  // tells timed_changed_ when timed commands run or did
  std::string lostHeartbeat() const;
  std::string channelNames(const std::vector<uint8_t>& channels) const;

  // What the device's self-timed outputs show (none: every output shows its coil).
  bool runsNow(size_t ch) const { return timed_ && timed_->outputSelfTimed(ch); }
  bool runReadByLastPoll(size_t ch) const { return !timed_ || timed_->selfTimedReadByLastPoll(ch); }
  bool runsRead() const { return !timed_ || timed_->selfTimedRead(); }
  std::vector<uint8_t> timedStoppedBy(const Request& request) const;

  Device& device_;
  SelfTimedOutputs* const timed_;  // device_.selfTimed(): its outputs timed by itself, or none
  BusScheduler& scheduler_;
  ChannelIntents intents_;
  std::unique_ptr<Watchdog> heartbeat_;
  const Watchdog* bus_heartbeat_ = nullptr;
  std::string bus_heartbeat_topic_;
  ReportSink sink_;
  std::function<void()> outputs_written_;
  std::function<void(const std::vector<TimedIntent>&)> timed_changed_;
  // The last list told, its ends in the clock's seconds (bus thread): told again only when it
  // changed, as it is looked at after every poll.
  std::vector<KeptTimedCommand> timed_told_;
  // afterPoll's per-channel scratch (bus thread), kept so that a poll allocates none.
  std::vector<bool> poll_timed_, poll_read_now_;

  mutable std::mutex mutex_;  // the counters and texts below
  uint64_t restarts_detected_ = 0, events_ = 0;
  std::string last_event_;
  std::string active_;  // set by a safe write, cleared by a user's confirmed command
  Trigger active_trigger_ = Trigger::kRestart;  // the trigger of that safe write
};

}  // namespace modbus_rtu_driver
