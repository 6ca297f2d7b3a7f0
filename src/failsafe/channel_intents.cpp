#include "modbus_rtu_driver/failsafe/channel_intents.h"

#include <algorithm>
#include <chrono>
#include <map>

#include "modbus_rtu_driver/core/modbus/text.h"

namespace modbus_rtu_driver {

namespace {

constexpr NameTable<CommandSource, 7> kCommandSourceNames{{{CommandSource::kFound, "found"},
                                                           {CommandSource::kUser, "user"},
                                                           {CommandSource::kShare, "share"},
                                                           {CommandSource::kRaw, "raw write"},
                                                           {CommandSource::kTimed, "timed"},
                                                           {CommandSource::kRestore, "restore"},
                                                           {CommandSource::kSafe, "safe"}}};

Clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

const char* commandSourceName(CommandSource source) {
  return nameIn(kCommandSourceNames, source).data();  // literals: terminated
}

ChannelIntents::ChannelIntents(FailsafeConfig config, size_t channels, Clock& clock)
    : config_(std::move(config)), channels_(channels), clock_(clock), ch_(channels) {}

OutputTargets ChannelIntents::safeTargets() const {
  return config_.safeTargets(channels_);
}

// A command from outside the fail-safe (a user, a share client, a raw write, a timed command)
// ends the holds on its channel and cancels what the fail-safe still owed it: the newest command
// wins. The fail-safe's own writes (restore, safe) pay what they owed and hold nothing.
bool ChannelIntents::userSource(CommandSource source) const {
  return source != CommandSource::kRestore && source != CommandSource::kSafe &&
         source != CommandSource::kFound;
}

void ChannelIntents::newCommand(uint8_t channel, CommandSource source) {
  write_during_poll_ = true;
  if (source == CommandSource::kFound) return;  // an outcome unknown: nothing paid or ended
  ch_[channel].owed.reset();
  if (userSource(source)) ch_[channel].held = 0;
}

void ChannelIntents::commanded(const std::vector<uint8_t>& channels,
                               const std::vector<bool>& levels, CommandSource source) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto now = clock_.now();
  for (size_t i = 0; i < channels.size() && i < levels.size(); ++i) {
    const uint8_t ch = channels[i];
    if (ch >= channels_) continue;
    Intent in;
    in.source = source;
    in.at = now;
    in.level = levels[i];
    ch_[ch].intent = in;
    newCommand(ch, source);
    ch_[ch].held_not_safe = false;  // the device shows this level now, not what the poll showed
    const bool safe_level = config_.safeStateOf(ch) == SafeState::kOn;
    if (ch_[ch].held != 0 && levels[i] == safe_level &&
        (source == CommandSource::kSafe || source == CommandSource::kRestore))
      ch_[ch].held_written = true;
  }
}

void ChannelIntents::timed(const TimedIntent& timed, CommandSource source) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (timed.channel >= channels_) return;
  const auto now = clock_.now();
  Intent in;
  in.source = source;
  in.at = now;
  in.level = timed.after;
  in.during = timed.during;
  if (timed.seconds < 0) {
    in.driven = true;
    in.restart = timed.restart;
  } else {
    in.ends = now + seconds(timed.seconds);
  }
  ch_[timed.channel].intent = in;
  newCommand(timed.channel, source);
}

// An intent the next poll fills in (adopt), keeping the channel's last level meanwhile.
ChannelIntents::Intent ChannelIntents::adoptingIntent(uint8_t channel, CommandSource source,
                                                      Clock::time_point now) const {
  Intent in;
  in.source = source;
  in.at = now;
  in.adopt = true;
  if (const std::optional<Intent>& was = ch_[channel].intent) in.level = was->level;
  return in;
}

void ChannelIntents::adoptNextPoll(uint8_t channel, CommandSource source, double not_before_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  adoptNextPollLocked(channel, source, not_before_s);
}

ChannelIntents::Intent* ChannelIntents::adoptNextPollLocked(uint8_t channel, CommandSource source,
                                                            double not_before_s) {
  if (channel >= channels_) return nullptr;
  const auto now = clock_.now();
  Intent in = adoptingIntent(channel, source, now);
  if (not_before_s > 0) in.adopt_from = now + seconds(not_before_s);
  // A timed command still running there (a write over a flash, heard or not): either level may
  // show until its end, so the poll that decides comes after its end plus the slack. Its end
  // may have passed by now (the write's timeout and its read back outlast the flash), but not
  // its slack: polls within it may still show either level (docs/failsafe.md line 105).
  const auto& was = ch_[channel].intent;
  if (was && was->ends) {
    const Clock::time_point settled = *was->ends + endSlack(was->at, *was->ends);
    if (settled > now) in.adopt_from = std::max(in.adopt_from.value_or(now), settled);
  }
  // An earlier lost write there already waits for such an end: whichever write the device
  // heard, the timed command may still run, so this one waits as long.
  if (was && was->adopt && was->adopt_from && *was->adopt_from > now) {
    in.adopt_from = std::max(in.adopt_from.value_or(now), *was->adopt_from);
  }
  // The run the device drove there goes on whatever the write did, where coil writes keep runs.
  if (was && was->adopt) {
    in.run_ends = was->run_ends;
    in.run_driven = was->run_driven;
    in.lost_run_ends = was->lost_run_ends;
    in.lost_run_driven = was->lost_run_driven;
  } else if (was && (was->driven || (was->ends && *was->ends > now))) {
    in.run_ends = was->ends;
    in.run_driven = was->driven;
  }
  newCommand(channel, source);  // it leaves the intent alone
  return &ch_[channel].intent.emplace(in);
}

void ChannelIntents::adoptRunNextPoll(uint8_t channel, CommandSource source, double seconds_run,
                                      double not_before_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  Intent* in = adoptNextPollLocked(channel, source, not_before_s);
  if (in == nullptr) return;
  if (seconds_run < 0) {
    in->lost_run_driven = true;
    return;
  }
  // Until its end plus the slack (F31, F32), counted from now: the device, if it heard the
  // write, started it before the node learned that its answer was lost.
  const auto now = clock_.now();
  const auto end = now + seconds(seconds_run);
  in->lost_run_ends = std::max(in->lost_run_ends.value_or(now), end + endSlack(now, end));
}

void ChannelIntents::stoppedNextPoll(uint8_t channel, CommandSource source) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (channel >= channels_) return;
  ch_[channel].intent = adoptingIntent(channel, source, clock_.now());
  newCommand(channel, source);
}

void ChannelIntents::adoptChangeNextPoll(uint8_t channel, CommandSource source) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (channel >= channels_) return;
  const auto now = clock_.now();
  Intent in = adoptingIntent(channel, source, now);
  in.adopt_change = true;
  const Expectation e = expectedLocked(channel, now);
  if (e.kind == Expectation::Kind::kLevel) in.adopt_prev = e.level;
  // A held channel the last poll showed otherwise, not yet written safe again: the device
  // shows the other level, so a stop that leaves it there changed nothing (docs/failsafe.md).
  if (ch_[channel].held != 0 && ch_[channel].held_not_safe)
    in.adopt_prev = config_.safeStateOf(channel) != SafeState::kOn;
  ch_[channel].intent = in;
  write_during_poll_ = true;  // holds and owed writes end at the poll, if it changed
}

void ChannelIntents::adoptChangesNextPoll(CommandSource source) {
  std::lock_guard<std::mutex> lock(mutex_);
  adopt_changes_ = source;
  write_during_poll_ = true;
}

void ChannelIntents::writeRan() {
  std::lock_guard<std::mutex> lock(mutex_);
  write_during_poll_ = true;
}

namespace {
uint8_t bitOf(Trigger trigger) {
  return static_cast<uint8_t>(1u << static_cast<unsigned>(trigger));
}
}  // namespace

void ChannelIntents::hold(const std::vector<uint8_t>& channels, Trigger trigger) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto now = clock_.now();
  const auto holdOne = [&](size_t ch) {
    if (ch >= channels_ || config_.safeStateOf(ch) == SafeState::kLeave) return;
    if (ch_[ch].held == 0) {
      ch_[ch].held_since = now;
      ch_[ch].held_written = false;
    }
    ch_[ch].held |= bitOf(trigger);
  };
  if (channels.empty()) {
    for (size_t ch = 0; ch < channels_; ++ch) holdOne(ch);
  } else {
    for (uint8_t ch : channels) holdOne(ch);
  }
}

OutputTargets ChannelIntents::heldTargets(const std::vector<uint8_t>& only) const {
  std::lock_guard<std::mutex> lock(mutex_);
  OutputTargets t;
  for (size_t ch = 0; ch < channels_; ++ch) {
    if (ch_[ch].held == 0) continue;
    if (!only.empty() && std::find(only.begin(), only.end(), ch) == only.end()) continue;
    t.channels.push_back(static_cast<uint8_t>(ch));
    t.states.push_back(config_.safeStateOf(ch) == SafeState::kOn);
  }
  return t;
}

bool ChannelIntents::anyHeld() const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const Channel& c : ch_)
    if (c.held != 0) return true;
  return false;
}

std::vector<uint8_t> ChannelIntents::heldNotSafe() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<uint8_t> chs;
  for (size_t ch = 0; ch < channels_; ++ch)
    if (ch_[ch].held != 0 && ch_[ch].held_not_safe) chs.push_back(static_cast<uint8_t>(ch));
  return chs;
}

bool ChannelIntents::held(uint8_t channel) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return channel < channels_ && ch_[channel].held != 0;
}

bool ChannelIntents::heldBy(uint8_t channel, Trigger trigger) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return channel < channels_ && (ch_[channel].held & bitOf(trigger)) != 0;
}

void ChannelIntents::owe(const OutputTargets& targets, Clock::time_point since) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (size_t i = 0; i < targets.channels.size() && i < targets.states.size(); ++i) {
    const uint8_t ch = targets.channels[i];
    if (ch >= channels_) continue;
    // A command confirmed after the trigger is newer: the trigger no longer speaks for it.
    const auto& in = ch_[ch].intent;
    if (in && userSource(in->source) && in->at > since) continue;
    ch_[ch].owed = Owed{targets.states[i], since};
  }
}

OutputTargets ChannelIntents::owed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  OutputTargets t;
  for (size_t ch = 0; ch < channels_; ++ch) {
    const std::optional<Owed>& o = ch_[ch].owed;
    if (!o) continue;
    t.channels.push_back(static_cast<uint8_t>(ch));
    t.states.push_back(o->level);
  }
  return t;
}

Clock::duration ChannelIntents::endSlack(Clock::time_point at, Clock::time_point ends) {
  return seconds(kEndSlackSeconds) +
         std::chrono::duration_cast<Clock::duration>((ends - at) * kEndSlackFraction);
}

std::vector<uint8_t> ChannelIntents::pollStarting() {
  std::lock_guard<std::mutex> lock(mutex_);
  write_during_poll_ = false;
  poll_started_at_ = clock_.now();
  std::vector<uint8_t> due;
  for (size_t ch = 0; ch < channels_; ++ch) {
    const auto& in = ch_[ch].intent;
    if (in && in->adopt && (!in->adopt_from || *in->adopt_from <= poll_started_at_))
      due.push_back(static_cast<uint8_t>(ch));
  }
  return due;
}

Expectation ChannelIntents::expected(uint8_t channel, Clock::time_point t) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return expectedLocked(channel, t);
}

std::vector<bool> ChannelIntents::timedMayRun() const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto now = clock_.now();
  std::vector<bool> may_run(channels_, false);
  for (size_t ch = 0; ch < channels_; ++ch) {
    const std::optional<Intent>& slot = ch_[ch].intent;
    if (!slot) continue;
    const Intent& in = *slot;
    if (in.ends && !in.driven && now <= *in.ends + endSlack(in.at, *in.ends)) may_run[ch] = true;
    if (in.adopt && in.run_ends && now <= *in.run_ends + endSlack(in.at, *in.run_ends))
      may_run[ch] = true;
    if (in.adopt && in.lost_run_ends && now <= *in.lost_run_ends) may_run[ch] = true;
  }
  return may_run;
}

Expectation ChannelIntents::expectedLocked(uint8_t channel, Clock::time_point t) const {
  Expectation e;
  if (channel >= channels_) return e;
  const std::optional<Intent>& slot = ch_[channel].intent;
  if (!slot) return e;
  const Intent& in = *slot;
  if (in.adopt || in.driven) return e;
  e.level = in.level;
  if (!in.ends) {
    e.kind = Expectation::Kind::kLevel;
    return e;
  }
  const auto slack = endSlack(in.at, *in.ends);
  if (t < *in.ends - slack) {
    if (!in.during) return Expectation{};  // the device switches it by itself meanwhile
    e.kind = Expectation::Kind::kLevel;
    e.level = *in.during;
  } else if (t <= *in.ends + slack) {
    e.kind = Expectation::Kind::kEither;
  } else {
    e.kind = Expectation::Kind::kLevel;
  }
  return e;
}

ChannelIntents::Verdict ChannelIntents::observePoll(const std::vector<bool>& outputs,
                                                    const std::vector<bool>& self_timed,
                                                    bool was_offline, std::vector<uint8_t>* changed,
                                                    const std::vector<bool>& read_now) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (changed) changed->clear();
  for (Channel& c : ch_) c.held_not_safe = false;
  const auto now = clock_.now();
  if (write_during_poll_) {
    // What it read may predate that write: neither a restart nor an intent to adopt. A run it
    // read is still the device's report, on a channel not commanded since the poll started (a
    // power-down save's run, seen by the one poll in 8 that reads its registers, would be
    // missed, and its end later taken for a restart).
    write_during_poll_ = false;
    for (size_t ch = 0; ch < channels_ && ch < self_timed.size(); ++ch) {
      const auto& in = ch_[ch].intent;
      if (self_timed[ch] && (ch >= read_now.size() || read_now[ch]) && in && !in->adopt &&
          in->at <= poll_started_at_)
        deviceRunsLocked(static_cast<uint8_t>(ch), now);
    }
    return was_offline ? Verdict::kCameBack : Verdict::kNormal;
  }
  bool differs = false;
  for (size_t ch = 0; ch < channels_ && ch < outputs.size(); ++ch) {
    auto& in = ch_[ch].intent;
    const bool device_runs = ch < self_timed.size() && self_timed[ch];
    if (!in) {
      // Found at the node's start (or never commanded): that is what a restore puts back. A
      // PWM the device runs is the device's: not compared, not restored (docs/failsafe.md).
      Intent found;
      found.at = now;
      found.level = outputs[ch];
      found.driven = device_runs;
      in = found;
      continue;
    }
    if (in->adopt) {
      if (in->adopt_from && now < *in->adopt_from) continue;  // it may still run
      // Whether the device runs a PWM there, as read now: an older snapshot may miss a run.
      if (ch < read_now.size() && !read_now[ch]) continue;
      const bool level = outputs[ch];
      const bool client = in->source == CommandSource::kShare || in->source == CommandSource::kRaw;
      if (in->adopt_change) {
        // What the write changed is its command; a level it did not change is not (a hold
        // that began after the write is newer than it).
        const bool differs_now = in->adopt_prev && *in->adopt_prev != level;
        if (differs_now && !(ch_[ch].held != 0 && ch_[ch].held_since > in->at)) {
          ch_[ch].held = 0;
          ch_[ch].owed.reset();
          took_adopted_ = true;
        } else {
          in->source = CommandSource::kFound;
        }
      } else if (client) {
        took_adopted_ = true;
      }
      in->adopt_from.reset();
      in->adopt_prev.reset();
      in->level = level;
      // A stop the type decoded ended the run, whatever the device's PWM snapshot (up to a
      // few polls old) still says.
      in->driven = device_runs && !in->adopt_change;
      in->ends.reset();
      in->during.reset();
      in->adopt = in->adopt_change = false;
      // A level taken as found ends no hold: a held channel shown otherwise (a command whose
      // answer was lost) is written safe again (docs/failsafe.md, precedence 1).
      if (ch_[ch].held != 0 && ch_[ch].held_written &&
          (in->driven || level != (config_.safeStateOf(ch) == SafeState::kOn)))
        ch_[ch].held_not_safe = true;
      continue;
    }
    if (ch_[ch].held != 0 && ch_[ch].held_written &&
        (device_runs || outputs[ch] != (config_.safeStateOf(ch) == SafeState::kOn)))
      ch_[ch].held_not_safe = true;
    if (in->restart && !device_runs && (ch >= read_now.size() || read_now[ch])) {
      // The node's continuous run, read stopped with no stop carried (that would have replaced
      // the intent): the LD58A08 does not stop one by itself, a power cycle does
      // (docs/failsafe.md, "Restart detection needs polls"). A restore starts it again; under
      // the other policies the level is taken as it is, so the next poll does not count it again.
      differs = true;
      if (changed) changed->push_back(static_cast<uint8_t>(ch));
      if (config_.on_restart != OnRestart::kRestore) {
        Intent found;
        found.at = now;
        found.level = outputs[ch];
        in = found;
      }
      continue;
    }
    if (device_runs) {
      // The device's PWM drives it. A run that is no timed command of the node's still running
      // (one a power-down save restarted, one someone else started) has no end the node knows:
      // the channel is not compared until a plain write settles it again (docs/failsafe.md,
      // "Restart detection needs polls"), also after the device reports the run ended. Only
      // as this poll read it: an older snapshot may still show a run that has ended.
      if (ch >= read_now.size() || read_now[ch]) deviceRunsLocked(static_cast<uint8_t>(ch), now);
      continue;
    }
    const Expectation e = expectedLocked(static_cast<uint8_t>(ch), now);
    if (e.kind == Expectation::Kind::kAny) continue;
    if (e.kind == Expectation::Kind::kEither) {
      // The final level near the end: the timed command ended (settled). Not for a run the
      // device toggles (a burst): its off phase shows the final level before the end too.
      if (outputs[ch] == e.level && (in->during || now >= *in->ends)) in->ends.reset();
      continue;
    }
    // The outputs were read at some time since the poll started (queued jobs run between a
    // poll's transactions: seconds, with a silent device's retries): a level the channel
    // should have shown then is no change either (a flash that ended meanwhile).
    const Expectation then = expectedLocked(static_cast<uint8_t>(ch), poll_started_at_);
    if (in->ends && now > *in->ends) in->ends.reset();  // ended and shown: a steady level now
    if (outputs[ch] == e.level) continue;
    if (then.kind != Expectation::Kind::kLevel || outputs[ch] == then.level) continue;
    if (adopt_changes_) {
      // Someone else's confirmed register write (a flash, a PWM through registers): a command.
      Intent adopted;
      adopted.source = *adopt_changes_;
      adopted.at = now;
      adopted.level = outputs[ch];
      in = adopted;
      ch_[ch].held = 0;
      ch_[ch].owed.reset();
      took_adopted_ = true;
      continue;
    }
    differs = true;
    if (changed) changed->push_back(static_cast<uint8_t>(ch));
    // What on_restart will not write back is taken as it is now, so the next poll does not
    // count the same restart again.
    const bool rewritten =
        config_.on_restart == OnRestart::kRestore ||
        (config_.on_restart == OnRestart::kSafe && config_.safeStateOf(ch) != SafeState::kLeave);
    if (!rewritten && !ch_[ch].owed) {
      Intent found;
      found.at = now;
      found.level = outputs[ch];
      in = found;
    }
  }
  adopt_changes_.reset();
  if (was_offline) return Verdict::kCameBack;
  return differs ? Verdict::kOutputsChanged : Verdict::kNormal;
}

void ChannelIntents::deviceRunsLocked(uint8_t channel, Clock::time_point now) {
  auto& in = ch_[channel].intent;
  if (!in) return;
  const Expectation e = expectedLocked(channel, now);
  if (!in->ends || e.kind == Expectation::Kind::kLevel) in->driven = true;
}

void ChannelIntents::observeRuns(const std::vector<bool>& runs) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto now = clock_.now();
  for (size_t ch = 0; ch < channels_ && ch < runs.size(); ++ch)
    if (runs[ch]) deviceRunsLocked(static_cast<uint8_t>(ch), now);
}

void ChannelIntents::observeRunsOfFailedPoll(const std::vector<bool>& runs) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto now = clock_.now();
  for (size_t ch = 0; ch < channels_ && ch < runs.size(); ++ch) {
    const auto& in = ch_[ch].intent;
    if (runs[ch] && in && !in->adopt && in->at <= poll_started_at_)
      deviceRunsLocked(static_cast<uint8_t>(ch), now);
  }
}

bool ChannelIntents::tookAdoptedWrite() {
  std::lock_guard<std::mutex> lock(mutex_);
  const bool took = took_adopted_;
  took_adopted_ = false;
  return took;
}

OutputTargets ChannelIntents::afterPollTargets(Verdict verdict,
                                               const std::vector<bool>& device_runs) const {
  std::map<uint8_t, bool> by_channel;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto now = clock_.now();
    if (verdict != Verdict::kNormal && config_.on_restart == OnRestart::kRestore) {
      for (size_t ch = 0; ch < channels_; ++ch) {
        const auto c = static_cast<uint8_t>(ch);
        if (ch_[ch].held != 0) {
          by_channel[c] = config_.safeStateOf(ch) == SafeState::kOn;
          continue;
        }
        const std::optional<Intent>& known = ch_[ch].intent;  // one name: clang-tidy 19
        if (!known) continue;
        const Intent& in = *known;
        // A timed command a restart interrupted is not started again (that would repeat
        // something that started): its final level is restored. A run the device drives with
        // no end is not restored (docs/failsafe.md, "What restore writes").
        if (in.driven || in.adopt) continue;
        if (in.ends) {
          by_channel[c] = in.level;
          continue;
        }
        // A PWM the device runs that is no timed command of the node's (a client's run whose
        // answer was lost, one the device restarted) is the device's: a restore does not stop it.
        if (ch < device_runs.size() && device_runs[ch]) continue;
        const Expectation e = expectedLocked(c, now);
        if (e.kind != Expectation::Kind::kAny) by_channel[c] = e.level;
      }
    }
    for (size_t ch = 0; ch < channels_; ++ch)
      if (const std::optional<Owed>& o = ch_[ch].owed)
        by_channel[static_cast<uint8_t>(ch)] = o->level;
    // A hold keeps its channels safe whatever on_restart says (docs/failsafe.md, precedence).
    for (size_t ch = 0; ch < channels_; ++ch)
      if (ch_[ch].held != 0 && ch_[ch].held_not_safe)
        by_channel[static_cast<uint8_t>(ch)] = config_.safeStateOf(ch) == SafeState::kOn;
  }
  if (verdict != Verdict::kNormal && config_.on_restart == OnRestart::kSafe) {
    const OutputTargets safe = safeTargets();
    for (size_t i = 0; i < safe.channels.size(); ++i)
      by_channel.emplace(safe.channels[i], safe.states[i]);  // owed states stay over them
  }
  OutputTargets t;
  for (const auto& [channel, state] : by_channel) {
    t.channels.push_back(channel);
    t.states.push_back(state);
  }
  return t;
}

std::vector<TimedIntent> ChannelIntents::runsToStartAgain(
    Verdict verdict, const std::vector<bool>& device_runs) const {
  std::vector<TimedIntent> again;
  if (verdict == Verdict::kNormal || config_.on_restart != OnRestart::kRestore) return again;
  std::lock_guard<std::mutex> lock(mutex_);
  for (size_t ch = 0; ch < channels_ && ch < device_runs.size(); ++ch) {
    const auto& in = ch_[ch].intent;
    if (!in || !in->driven || !in->restart || device_runs[ch] || ch_[ch].held != 0 || ch_[ch].owed)
      continue;
    TimedIntent t;
    t.channel = static_cast<uint8_t>(ch);
    t.after = in->level;
    t.restart = in->restart;
    again.push_back(t);
  }
  return again;
}

std::vector<bool> ChannelIntents::runsUnderAdoption(bool driven_too) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<bool> runs(channels_, false);
  const auto now = clock_.now();
  for (size_t ch = 0; ch < channels_; ++ch) {
    const auto& in = ch_[ch].intent;
    if (!in || !in->adopt) continue;
    runs[ch] = (in->run_ends && *in->run_ends > now) || (driven_too && in->run_driven);
  }
  return runs;
}

std::vector<bool> ChannelIntents::lostRunsUnderAdoption() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<bool> runs(channels_, false);
  const auto now = clock_.now();
  for (size_t ch = 0; ch < channels_; ++ch) {
    const auto& in = ch_[ch].intent;
    if (!in || !in->adopt) continue;
    runs[ch] = (in->lost_run_ends && *in->lost_run_ends > now) || in->lost_run_driven;
  }
  return runs;
}

std::vector<TimedIntent> ChannelIntents::runningTimed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<TimedIntent> running;
  const auto now = clock_.now();
  for (size_t ch = 0; ch < channels_; ++ch) {
    const auto& in = ch_[ch].intent;
    if (!in || (!in->driven && !in->ends) || (in->ends && *in->ends <= now)) continue;
    TimedIntent t;
    t.channel = static_cast<uint8_t>(ch);
    t.during = in->during;
    t.after = in->level;
    t.seconds = in->ends ? std::chrono::duration<double>(*in->ends - now).count() : -1.0;
    running.push_back(t);
  }
  return running;
}

void ChannelIntents::resumeTimed(const std::vector<TimedIntent>& running) {
  // Not a command of this node's: nothing held is ended, nothing owed is paid (kFound).
  for (const TimedIntent& t : running) timed(t, CommandSource::kFound);
}

void ChannelIntents::commandReceived(uint8_t channel, bool state) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (channel >= channels_) return;
  const double timeout = config_.commandTimeoutOf(channel);
  if (state && timeout > 0) {
    ch_[channel].command_deadline = clock_.now() + seconds(timeout);
  } else {
    ch_[channel].command_deadline.reset();
  }
}

std::vector<uint8_t> ChannelIntents::expiredCommands() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<uint8_t> expired;
  const auto now = clock_.now();
  for (size_t i = 0; i < channels_; ++i) {
    std::optional<Clock::time_point>& deadline = ch_[i].command_deadline;
    if (!deadline || now < *deadline) continue;
    deadline.reset();
    expired.push_back(static_cast<uint8_t>(i));
  }
  return expired;
}

}  // namespace modbus_rtu_driver
