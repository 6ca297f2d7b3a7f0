#include "modbus_rtu_driver/failsafe/device_failsafe.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/devices/output_batch.h"

namespace modbus_rtu_driver {

std::string FailsafeReport::runsStartedText() const {
  std::vector<std::string> started;
  for (size_t i = 0; i < channels.size() && i < runs.size(); ++i)
    if (runs[i]) started.push_back(channels[i]);
  return "PWM run started again on " + join(started);
}

std::string FailsafeReport::text() const {
  std::string t = std::string(triggerName(trigger)) + " (" + reason + "): ";
  std::vector<std::string> changes;
  for (size_t i = 0; i < channels.size() && i < states.size(); ++i)
    changes.push_back(channels[i] + (i < runs.size() && runs[i] ? " PWM run started again"
                                     : states[i]                ? " on"
                                                                : " off"));
  t += join(changes);
  if (channels.empty()) t += actionName(action);
  if (!confirmed) t += "; NOT confirmed: " + message;
  return t;
}

DeviceFailsafe::DeviceFailsafe(Device& device, BusScheduler& scheduler, Clock& clock)
    : device_(device),
      timed_(device.selfTimed()),
      scheduler_(scheduler),
      intents_(device.config().failsafe, device.outputCount(), clock) {
  const FailsafeConfig& fs = intents_.config();
  if (!fs.heartbeat_topic.empty())
    heartbeat_ = std::make_unique<Watchdog>(fs.heartbeat_timeout, clock);
}

void DeviceFailsafe::setBusHeartbeat(const Watchdog* heartbeat, std::string topic) {
  bus_heartbeat_ = heartbeat;
  bus_heartbeat_topic_ = std::move(topic);
}

std::string DeviceFailsafe::channelNames(const std::vector<uint8_t>& channels) const {
  const auto names = device_.outputNames();
  return join(channels, ", ", [&names](uint8_t c) { return names[c]; });
}

std::future<Result> DeviceFailsafe::applySafe(Trigger trigger, const std::string& reason,
                                              const std::vector<uint8_t>& only) {
  // A trigger that lasts holds its channels safe on every restore until they are commanded
  // again, even if this write does not get through; what the write sets is read from the holds
  // when the bus gets to it, so a channel commanded in between is left as commanded.
  const bool lasting = holdsChannels(trigger);
  const auto since = intents_.clock().now();
  OutputTargets targets;
  if (lasting) {
    intents_.hold(only, trigger);
    targets = intents_.heldTargets(only);
  } else {
    const OutputTargets all = intents_.safeTargets();
    for (size_t i = 0; i < all.channels.size(); ++i) {
      if (!only.empty() && std::find(only.begin(), only.end(), all.channels[i]) == only.end())
        continue;
      targets.channels.push_back(all.channels[i]);
      targets.states.push_back(all.states[i]);
    }
  }
  if (targets.empty()) return readyResult(Result::success());
  return scheduler_.submit(
      device_.name(), [this, lasting, only, targets, trigger, reason, since](Transport& t) {
        const OutputTargets now = lasting ? intents_.heldTargets(only) : targets;
        if (now.empty()) return Result::success();  // commanded again before the bus got to it
        // A write of every safe channel (a node stop, on_start): it carries the channels commanded
        // since the trigger too, so what it owes is stamped when it went out (docs/failsafe.md
        // F40).
        if (!lasting)
          return writeAndReport(t, now, trigger, reason, Action::kSafe, intents_.clock().now());
        // A device silent since its last answer costs the other devices' safe writes (queued
        // behind this one) its write alone: the read that tells whether the write got through
        // anyway goes after them (docs/failsafe.md, "Timing").
        UntilSilentTransport until_silent(t);
        return writeAndReport(until_silent, now, trigger, reason, Action::kSafe, since,
                              &until_silent, only);
      });
}

Result DeviceFailsafe::writeAndReport(Transport& t, const OutputTargets& targets, Trigger trigger,
                                      const std::string& reason, Action action,
                                      std::optional<Clock::time_point> owe_since,
                                      const UntilSilentTransport* until_silent,
                                      const std::vector<uint8_t>& held_only,
                                      const FailsafeReport* runs_started) {
  FailsafeReport r;
  r.device = device_.name();
  r.trigger = trigger;
  r.reason = reason;
  r.action = action;
  nameTargets(targets, &r);
  if (runs_started) {
    r.runs.assign(r.channels.size(), false);
    for (size_t i = 0; i < runs_started->channels.size(); ++i) {
      r.channels.push_back(runs_started->channels[i]);
      r.states.push_back(true);
      r.runs.push_back(true);
    }
    r.runs_failed = runs_started->runs_failed;
  }
  intents_.writeRan();
  Result w =
      OutputBatch::write(device_, t, targets.channels, targets.states, intents_.timedMayRun());
  if (until_silent && until_silent->refused()) {
    // The device gave no reply: its read back waits behind the queued safe writes (the bus
    // runs writes in the order queued), and this write's event comes with it.
    scheduler_.submit(device_.name(), [this, targets, r, w, owe_since,
                                       only = held_only](Transport& later) mutable {
      // Only the channels still held: one commanded meanwhile is its caller's now.
      const OutputTargets held = intents_.heldTargets(only);
      OutputTargets still;
      for (size_t i = 0; i < targets.channels.size(); ++i) {
        if (std::find(held.channels.begin(), held.channels.end(), targets.channels[i]) ==
            held.channels.end())
          continue;
        still.channels.push_back(targets.channels[i]);
        still.states.push_back(targets.states[i]);
      }
      if (still.empty()) return Result::success();
      nameTargets(still, &r);  // the event names the channels it settles (confirmed, or owed)
      // Whether it answers now: then the safe write again, confirmed by its answer and a read
      // back. A read alone cannot confirm a write that got no reply: a flash the write would
      // have ended may still show the same level.
      bool answered = false;
      const Result back = readBack(later, still, &answered);
      if (answered) return writeAndReport(later, still, r.trigger, r.reason, r.action, owe_since);
      w.message += "; then the read: " + back.message;
      return settle(still, std::move(w), std::move(r), owe_since);
    });
    return w;
  }
  if (w.ok()) {
    bool answered = false;
    const Result back = readBack(t, targets, &answered);
    if (!back.ok())
      w = answered ? back : Result::failure(back.error, "written, but " + back.message);
  }
  return settle(targets, std::move(w), std::move(r), owe_since);
}

void DeviceFailsafe::nameTargets(const OutputTargets& targets, FailsafeReport* r) const {
  const auto names = device_.outputNames();
  r->channels.clear();
  r->states.clear();
  for (size_t i = 0; i < targets.channels.size(); ++i) {
    r->channels.push_back(names[targets.channels[i]]);
    r->states.push_back(targets.states[i]);
  }
}

Result DeviceFailsafe::readBack(Transport& t, const OutputTargets& targets, bool* answered) {
  const auto names = device_.outputNames();
  // The outputs as the device reports them now, not as the write's echo said.
  const Result back = device_.poll(t);
  if (!back.ok()) return Result::failure(back.error, "reading back failed: " + back.message);
  if (answered) *answered = true;
  // The read back is a poll of the device: a run it shows on a channel this write left is the
  // device's, as a scheduled poll's would be (it also took that poll's turn).
  std::vector<bool> runs(device_.outputCount(), false);
  for (size_t ch = 0; ch < runs.size(); ++ch)
    runs[ch] =
        runReadByLastPoll(ch) && runsNow(ch) &&
        std::find(targets.channels.begin(), targets.channels.end(), ch) == targets.channels.end();
  intents_.observeRuns(runs);
  for (size_t i = 0; i < targets.channels.size(); ++i) {
    if (device_.outputs()[targets.channels[i]] == targets.states[i]) continue;
    return Result::failure(ErrorKind::kMalformed, "read back: " + names[targets.channels[i]] +
                                                      " is still " +
                                                      (targets.states[i] ? "off" : "on"));
  }
  return Result::success();
}

Result DeviceFailsafe::settle(const OutputTargets& targets, Result w, FailsafeReport r,
                              std::optional<Clock::time_point> owe_since,
                              const std::string& confirmed_text) {
  if (w.ok()) {
    // A safe write is a command like any other: a restore writes it again.
    intents_.commanded(
        targets.channels, targets.states,
        r.action == Action::kRestore ? CommandSource::kRestore : CommandSource::kSafe);
    if (outputs_written_) outputs_written_();
    // A restore with no channel held safe put back what users had: no longer in a safe state.
    if (r.action == Action::kRestore && !intents_.anyHeld()) endSafeState();
    timedMaybeChanged();
  } else if (owe_since) {
    // Owed per channel: written when the device answers again, unless commanded before that.
    intents_.owe(targets, *owe_since);
  }
  // A restore's runs started again count too (FailsafeReport::runs).
  r.levels_confirmed = w.ok();
  r.confirmed = w.ok() && r.runs_failed.empty();
  r.message = w.ok() ? confirmed_text : w.message;
  if (!r.runs_failed.empty())
    r.message += (r.message.empty() ? "" : "; ") + std::string("PWM run ") + r.runs_failed;
  else if (std::count(r.runs.begin(), r.runs.end(), true) > 0)
    r.message += (r.message.empty() ? "" : "; ") + r.runsStartedText();
  report(r);
  return w;
}

std::vector<uint8_t> DeviceFailsafe::timedStoppedBy(const Request& request) const {
  return timed_ ? timed_->timedStoppedBy(request) : std::vector<uint8_t>{};
}

void DeviceFailsafe::afterFailedPoll() {
  std::vector<bool> runs(device_.outputCount(), false);
  bool any = false;
  for (size_t ch = 0; ch < runs.size(); ++ch) {
    runs[ch] = runReadByLastPoll(ch) && runsNow(ch);
    any = any || runs[ch];
  }
  if (!any) return;
  intents_.observeRunsOfFailedPoll(runs);
  timedMaybeChanged();
}

void DeviceFailsafe::afterPoll() {
  // The scheduler records this poll after this callback: health still says how it was before.
  const bool was_offline = !scheduler_.online(device_.name());
  // Kept between polls (bus thread): no allocation a poll (issue 50).
  std::vector<bool>& timed = poll_timed_;
  std::vector<bool>& read_now = poll_read_now_;
  timed.assign(device_.outputCount(), false);
  read_now.assign(device_.outputCount(), false);
  for (size_t i = 0; i < timed.size(); ++i) {
    timed[i] = runsNow(i);
    read_now[i] = runReadByLastPoll(i);
  }
  std::vector<uint8_t> changed;
  const auto verdict =
      intents_.observePoll(device_.outputs(), timed, was_offline, &changed, read_now);
  timedMaybeChanged();  // a run read ended, a timed command's end shown, a level adopted
  // A share client or raw write changed outputs: "in their safe state" (which names the channels
  // the safe write set) is no longer true, as after a user's write.
  if (intents_.tookAdoptedWrite()) endSafeState();
  const bool owed = !intents_.owed().empty();
  const std::vector<uint8_t> held_not_safe = intents_.heldNotSafe();
  if (verdict == ChannelIntents::Verdict::kNormal && !owed && held_not_safe.empty()) return;
  Trigger trigger = Trigger::kRestart;
  std::string reason = "the device answers again; its safe state was not reached before";
  Action action = Action::kSafe;
  if (!owed && !held_not_safe.empty()) {
    // A hold puts its channels back (whatever on_restart says), named for its trigger.
    trigger = intents_.heldBy(held_not_safe.front(), Trigger::kHeartbeat)
                  ? Trigger::kHeartbeat
                  : Trigger::kCommandTimeout;
    reason = "held safe, but a poll shows " + channelNames(held_not_safe) + " otherwise";
  }
  if (verdict != ChannelIntents::Verdict::kNormal) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++restarts_detected_;
    }
    reason = verdict == ChannelIntents::Verdict::kCameBack
                 ? "answered again after being offline"
                 : "outputs " + channelNames(changed) +
                       " changed with no command in between (power cycle?)";
    const OnRestart policy = config().on_restart;
    // With on_restart: leave, only the owed and held safe states are written: say so.
    action = (owed || !held_not_safe.empty()) && policy == OnRestart::kLeave
                 ? Action::kSafe
                 : restartAction(policy);
    trigger = Trigger::kRestart;
  }
  // What to write is read when the write runs: a command confirmed before then is not undone.
  scheduler_.submit(device_.name(), [this, verdict, trigger, reason, action](Transport& t) {
    // A report of this restart when nothing is written.
    auto nothingWritten = [&](bool confirmed, const std::string& message) {
      FailsafeReport r;
      r.device = device_.name();
      r.trigger = trigger;
      r.reason = reason;
      r.action = action;
      r.confirmed = r.levels_confirmed = confirmed;
      r.message = message;
      r.note_only = confirmed && action == Action::kLeave && !hasSafeStates();
      report(r);
    };
    std::vector<bool> runs(device_.outputCount(), false);
    if (verdict != ChannelIntents::Verdict::kNormal && config().on_restart == OnRestart::kRestore) {
      // What runs is read just before the restore (docs/failsafe.md, "What restore writes").
      // Unread, a restore could stop a run the device restarted (a power-down save) where the
      // snapshot, up to 8 polls old, says none runs: nothing is written now, and the next poll
      // that answers decides again (the change, and what is owed, are still there).
      Result read = timed_ ? timed_->refreshSelfTimed(t) : Result::success();  // returned by move
      if (!read.ok()) {
        nothingWritten(false,
                       "nothing written: reading which PWM runs before the restore failed (" +
                           read.message + "); the next poll decides again");
        return read;
      }
      for (size_t i = 0; i < runs.size(); ++i) runs[i] = runsNow(i);
      if (runsRead()) intents_.observeRuns(runs);  // the device's from now on
    }
    // The node's continuous runs a power cycle stopped go first: the read back of the restore's
    // plain write then shows them running, as the node's.
    // One report names them with the plain writes (FailsafeReport::runs).
    const std::vector<TimedIntent> again = intents_.runsToStartAgain(verdict, runs);
    FailsafeReport started;
    Result runs_result = startRunsAgain(t, again, &started);
    const OutputTargets targets = intents_.afterPollTargets(verdict, runs);
    if (!targets.empty())
      return writeAndReport(t, targets, trigger, reason, action, {}, nullptr, {}, &started);
    if (!again.empty()) {
      started.device = device_.name();
      started.trigger = trigger;
      started.reason = reason;
      started.action = action;
      started.levels_confirmed = true;  // none
      started.confirmed = started.runs_failed.empty();
      started.message = started.confirmed ? started.runsStartedText() : started.runs_failed;
      report(started);
      return runs_result;
    }
    if (verdict == ChannelIntents::Verdict::kNormal) return Result::success();
    nothingWritten(true, "outputs left as they are");  // trigger is kRestart here
    return Result::success();
  });
}

Result DeviceFailsafe::startRunsAgain(Transport& t, const std::vector<TimedIntent>& runs,
                                      FailsafeReport* r) {
  if (runs.empty()) return Result::success();
  const auto names = device_.outputNames();
  Result first_failure = Result::success();
  for (const TimedIntent& run : runs) {
    if (!run.restart) continue;  // runsToStartAgain gives only runs with their request
    intents_.writeRan();
    // Only a self-timed output's run has a write to start it again (runsToStartAgain).
    const Result w =
        timed_ ? timed_->startAgain(t, *run.restart)
               : Result::failure(ErrorKind::kInvalidArgument,
                                 std::string("a ") + device_.type() +
                                     " has no run to start again: " + run.restart->describe());
    r->channels.push_back(names[run.channel]);
    r->states.push_back(true);
    r->runs.push_back(true);
    if (w.ok()) {
      intents_.timed(run, CommandSource::kRestore);
      continue;
    }
    // Its answer lost and the read back too: it may run or not; the next poll that reads the
    // channel tells (docs/failsafe.md, "A command whose answer was lost").
    if (outcomeUnknown(w.error)) adoptAfterLost(run);
    r->runs_failed += (r->runs_failed.empty() ? "" : "; ") + names[run.channel] + ": " + w.message;
    if (first_failure.ok()) first_failure = w;
  }
  timedMaybeChanged();
  if (outputs_written_) outputs_written_();
  return first_failure;
}

std::vector<DeviceFailsafe::Fired> DeviceFailsafe::firedTriggers() {
  std::vector<Fired> fired;
  const auto expired = intents_.expiredCommands();
  if (!expired.empty())
    fired.push_back({Trigger::kCommandTimeout,
                     "no command on " + channelNames(expired) + " within its command_timeout",
                     expired});
  if (heartbeat_ && heartbeat_->expired()) {
    const FailsafeConfig& fs = config();
    fired.push_back({Trigger::kHeartbeat,
                     "no message on " + fs.heartbeat_topic + " within " +
                         numberText(fs.heartbeat_timeout) + " s",
                     {}});
  }
  return fired;
}

void DeviceFailsafe::checkDeadlines() {
  for (const Fired& f : firedTriggers()) applySafe(f.trigger, f.reason, f.only);
}

void DeviceFailsafe::userWriteConfirmed(const std::vector<uint8_t>& channels,
                                        const std::vector<bool>& states) {
  intents_.commanded(channels, states, CommandSource::kUser);
  endSafeState();
  timedMaybeChanged();  // a plain write replaces a timed command
}

void DeviceFailsafe::userWriteNotConfirmed(const std::vector<uint8_t>& channels,
                                           const Result& result,
                                           const std::vector<uint8_t>& changed) {
  // Refused, or never sent (port not open): nothing changed, but for what the device confirmed
  // before (docs/failsafe.md, "A write that failed after part of it was done"; a PWM run so
  // stopped no longer runs: its confirmed stop, as stop_pwm's). Its answer lost, or the port
  // failed after it may have gone out (kIo): the caller was told it failed, yet the device may
  // have acted; the next poll shows what the channels are (not a restart, not the caller's
  // command).
  const bool unknown = outcomeUnknown(result.error);
  for (uint8_t ch : changed) intents_.stoppedNextPoll(ch, CommandSource::kFound);
  if (unknown)
    for (uint8_t ch : channels) intents_.adoptNextPoll(ch, CommandSource::kFound);
  if (!changed.empty() || unknown)
    timedMaybeChanged();  // a timed command it may have replaced is no longer known to run
}

void DeviceFailsafe::timedCommandDone(const TimedIntent& intent, const Result& result) {
  if (result.ok()) {
    intents_.timed(intent, CommandSource::kTimed);
    endSafeState();
    timedMaybeChanged();
    return;
  }
  // Refused, or never sent (port not open): nothing started, the intent stays. The port
  // dropped mid-frame (kIo) or the answer was lost: it may run or not. Either level may show
  // until its end, then its final one is what a poll finds (it is not taken as commanded: the
  // caller was told it failed).
  // Not compared and not restored until its end; the first poll after it gives the channel's
  // level, taken as found (docs/failsafe.md, "A command whose answer was lost").
  if (!outcomeUnknown(result.error)) return;
  adoptAfterLost(intent);
  timedMaybeChanged();
}

void DeviceFailsafe::adoptAfterLost(const TimedIntent& intent) {
  const double until = intent.seconds < 0
                           ? 0.0
                           : intent.seconds * (1.0 + ChannelIntents::kEndSlackFraction) +
                                 ChannelIntents::kEndSlackSeconds;
  // The run it may have started goes on meanwhile (F31: a coil write over it keeps it), and the
  // device's snapshot says it runs until a read of the channel says otherwise.
  intents_.adoptRunNextPoll(intent.channel, CommandSource::kFound, intent.seconds, until);
  if (timed_) timed_->noteRunKept(intent.channel);
}

void DeviceFailsafe::externalWrite(const Request& request, const Result& result,
                                   CommandSource source) {
  // A broadcast (unit 0) confirms nothing: no device replies, and a silent one never heard it
  // (docs/failsafe.md, "What happens when"). Sent, it is as a write whose answer was lost.
  if (request.slave == kBroadcastAddress) {
    if (result.ok() || outcomeUnknown(result.error)) externalWriteLost(request);
    return;
  }
  if (result.ok())
    externalWriteConfirmed(request, source);
  else if (outcomeUnknown(result.error))
    externalWriteLost(request);
}

std::vector<bool> DeviceFailsafe::runsKeptOverCoilWrites() const {
  std::vector<bool> runs(device_.outputCount(), false);
  if (!timed_ || !timed_->coilWriteKeepsRun()) return runs;
  const bool read = runsRead();
  if (read)
    for (size_t ch = 0; ch < runs.size(); ++ch) runs[ch] = runsNow(ch);
  for (const TimedIntent& t : intents_.runningTimed())
    if (t.channel < runs.size() && (t.seconds >= 0 || !read)) runs[t.channel] = true;
  // A run a write whose outcome is unknown went over: the channel waits for the poll that tells
  // its level, but the run goes on (a coil write does not stop it).
  const std::vector<bool> adopted = intents_.runsUnderAdoption(!read);
  // A run a PWM write whose answer was lost may have started, unless a read since showed the
  // channel not running (F31).
  const std::vector<bool> lost = intents_.lostRunsUnderAdoption();
  for (size_t ch = 0; ch < runs.size() && ch < adopted.size(); ++ch)
    runs[ch] = runs[ch] || adopted[ch] || (lost[ch] && runsNow(ch));
  return runs;
}

void DeviceFailsafe::externalWriteLost(const Request& request) {
  for (uint8_t ch : device_.outputsWrittenBy(request).channels)
    intents_.adoptNextPoll(ch, CommandSource::kFound);
  for (const TimedIntent& t : device_.timedWrittenBy(request)) adoptAfterLost(t);
  for (uint8_t ch : timedStoppedBy(request)) intents_.adoptNextPoll(ch, CommandSource::kFound);
  timedMaybeChanged();
}

void DeviceFailsafe::timedCommandStopped(uint8_t channel, const Result& result) {
  if (!result.ok()) {
    // Its answer lost: stopped or not, the next poll that reads the channel tells (docs/
    // failsafe.md, "A command whose answer was lost"); refused or unsent: nothing changed.
    if (!outcomeUnknown(result.error)) return;
    intents_.adoptNextPoll(channel, CommandSource::kFound);
    timedMaybeChanged();
    return;
  }
  // The output shows the channel's coil again: the next poll says which level that is.
  intents_.stoppedNextPoll(channel, CommandSource::kTimed);
  endSafeState();
  timedMaybeChanged();
}

void DeviceFailsafe::externalWriteConfirmed(const Request& request, CommandSource source) {
  if (timed_) timed_->noteCarriedWrite(request);  // first: what follows reads its state now
  const OutputTargets set = device_.outputsWrittenBy(request);
  // A coil write on a channel the device runs a PWM on does not stop the run (the LD58A08
  // keeps it): a command (it ends holds) whose channel stays the device's (docs/failsafe.md:
  // a run read so, or one the node knows). A channel never read is commanded: if a run shows
  // at the next poll, the channel becomes the device's then (ChannelIntents::observePoll).
  // Runs: as the node last read them (a continuous run the device confirmed, and a run a coil
  // write kept, count as read running), and the node's timed commands before their end. A run
  // the device drives with no end (the device's, or a continuous one) counts from the intents
  // only while no read is known: a read since that shows it ended makes the write a plain one.
  const std::vector<bool> runs = runsKeptOverCoilWrites();
  for (size_t i = 0; i < set.channels.size(); ++i) {
    const uint8_t ch = set.channels[i];
    if (ch >= runs.size() || !runs[ch]) {
      intents_.commanded({ch}, {set.states[i]}, source);
      continue;
    }
    TimedIntent run;
    run.channel = ch;
    run.after = set.states[i];
    run.seconds = -1.0;
    intents_.timed(run, source);
    if (timed_) timed_->noteRunKept(ch);  // a later coil write finds it running too, until a read
  }
  const std::vector<TimedIntent> timed = device_.timedWrittenBy(request);
  for (const TimedIntent& t : timed) intents_.timed(t, source);
  const std::vector<uint8_t> stopped = timedStoppedBy(request);
  for (uint8_t ch : stopped) intents_.adoptChangeNextPoll(ch, source);
  if (!set.empty() || !timed.empty()) endSafeState();
  // Any other write (registers the type does not decode) shows at the next poll.
  if (set.empty() && timed.empty() && stopped.empty() && !isBitFunction(request.function))
    intents_.adoptChangesNextPoll(source);
  timedMaybeChanged();
}

void DeviceFailsafe::resumeTimed(const std::vector<TimedIntent>& running) {
  intents_.resumeTimed(running);
  // The kept list holds them already: without this, a resumed command dropped before any other
  // change left the list unchanged in our eyes (empty before, empty after) and was never told,
  // so the next node resumed a flash a lost write had replaced.
  const double now =
      std::chrono::duration<double>(intents_.clock().now().time_since_epoch()).count();
  timed_told_ = keepTimedCommands(intents_.runningTimed(), now);
}

void DeviceFailsafe::timedMaybeChanged() {
  const std::vector<TimedIntent> running = intents_.runningTimed();
  const double now =
      std::chrono::duration<double>(intents_.clock().now().time_since_epoch()).count();
  std::vector<KeptTimedCommand> kept = keepTimedCommands(running, now);
  auto same = [](const KeptTimedCommand& a, const KeptTimedCommand& b) {
    // The ends are now + seconds left: the same end, computed at two times, within rounding.
    return a.channel == b.channel && a.during == b.during && a.after == b.after &&
           std::abs(a.ends - b.ends) < 1e-3;
  };
  if (std::equal(kept.begin(), kept.end(), timed_told_.begin(), timed_told_.end(), same)) return;
  timed_told_ = std::move(kept);
  if (timed_changed_) timed_changed_(running);
}

void DeviceFailsafe::report(const FailsafeReport& r) {
  const std::string text = r.text();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++events_;
    last_event_ = text;
    if (!r.channels.empty() && r.action == Action::kSafe) {
      active_ = text;
      active_trigger_ = r.trigger;
    }
  }
  if (sink_) sink_(r);
}

void DeviceFailsafe::endSafeState() {
  std::lock_guard<std::mutex> lock(mutex_);
  active_.clear();
}

std::string DeviceFailsafe::lostHeartbeat() const {
  if (bus_heartbeat_ && bus_heartbeat_->tripped()) return bus_heartbeat_topic_;
  if (heartbeat_ && heartbeat_->tripped()) return config().heartbeat_topic;
  return "";
}

FailsafeStatus DeviceFailsafe::status() const {
  FailsafeStatus s;
  const FailsafeConfig& fs = config();
  const auto names = device_.outputNames();
  std::vector<std::string> states, held;
  for (size_t i = 0; i < names.size(); ++i) {
    if (fs.safeStateOf(i) != SafeState::kLeave)
      states.push_back(names[i] + " " + safeStateName(fs.safeStateOf(i)));
    if (intents_.held(static_cast<uint8_t>(i))) held.push_back(names[i]);
  }
  s.safe_states = states.empty() ? "none (every output holds)" : join(states);
  s.on_restart = onRestartName(fs.on_restart);
  s.lost_heartbeat = lostHeartbeat();
  if (bus_heartbeat_) s.bus_heartbeat_lost = bus_heartbeat_->tripped();
  if (heartbeat_) s.device_heartbeat_lost = heartbeat_->tripped();
  s.held = held.empty() ? "none" : join(held);
  const OutputTargets owed = intents_.owed();
  s.owed = owed.empty() ? "none" : channelNames(owed.channels);
  std::lock_guard<std::mutex> lock(mutex_);
  s.restarts_detected = restarts_detected_;
  s.events = events_;
  s.last_event = last_event_.empty() ? "none" : last_event_;
  // While a heartbeat is lost the controller is gone, whatever was written since; after it is
  // back the held channels are listed, and only the other triggers keep a WARN.
  if (!s.lost_heartbeat.empty()) {
    s.warn =
        "heartbeat lost (no message on " + s.lost_heartbeat + "): outputs held in their safe state";
  } else if (!active_.empty() && active_trigger_ != Trigger::kHeartbeat) {
    s.warn = "outputs in their safe state after " + active_;
  }
  return s;
}

}  // namespace modbus_rtu_driver
