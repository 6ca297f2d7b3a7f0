// World: polls, the fail-safe's reports and held channels (I2-I6, I8-I11).
#include "simulation_world.h"

namespace modbus_rtu_driver {
namespace simulation_world {

void World::onPollStarting(const std::string& device) {
  const int d = devOf(device);
  model_[d].poll_running = ++model_[d].polls_started;
  model_[d].in_poll = true;
  model_[d].written_in_poll = false;
  std::fill(model_[d].run_read_in_op.begin(), model_[d].run_read_in_op.end(), false);
  model_[d].readback_pending = false;
  model_[d].fs_written.assign(kChannels, false);
}

void World::onPolled(const std::string& device, const Result& r) {
  const int d = devOf(device);
  model_[d].in_poll = false;
  if (d == kGen || !r.ok()) return;
  DevModel& m = model_[d];
  const auto& outputs = node_->unit(device)->device().outputs();
  if (outputs.size() < kChannels) return;
  for (int ch = 0; ch < kChannels; ++ch) {
    Chan& c = m.ch[ch];
    // F32, F33: the poll that ends a timed command, as the node counts its end (from the
    // device's answer) and its slack: after the window any poll, within it one showing the
    // final level (for a run the device toggles, only from the end on). A poll during which a
    // write ran is not compared.
    if (c.known && c.timed && !c.settled && !c.adopt && !c.continuous && !m.written_in_poll) {
      const TP end = c.ends_earliest != TP{} ? c.ends_earliest : c.ends;
      const TP now = clock_.now();
      const Clock::duration slack = dur(0.5 + 0.02 * c.duration);
      if (now > end + slack ||
          (now >= end - slack && outputs[ch] == c.level && (c.during || now >= end)))
        c.settled = true;
    }
    c.shown_otherwise = c.held && outputs[ch] != safeLevel(d, ch);
    if (!m.found && !c.known && !c.adopt && !c.kept_uncertain && !m.written_in_poll) {
      // F22: where the node has commanded nothing, the intent is the state found at its
      // first good poll. A running PWM is the device's (F35).
      // A run as the node last read it (F24): an LD58A08 channel's registers, read before
      // the start's safe write, may be older than this poll.
      c.known = true;
      c.level = outputs[ch];
      c.continuous = d == kLd && m.pwm_read_running[ch];
      c.at = clock_.now();
      continue;
    }
    const bool registers_read = d != kLd || m.pwm_read_in_poll[ch] == m.poll_running;
    if (c.adopt && m.poll_running > c.adopt_after_poll && clock_.now() >= c.adopt_not_before &&
        registers_read && !m.written_in_poll) {
      // F49, F50, F26: what an undecoded write changed is taken as commanded at the next
      // poll; it ends a hold on the channels it changed.
      const bool level = outputs[ch];
      // F49, F50, F26: what the write changed is taken as commanded; a level that did not
      // change (or was not known) is not. Only a client's write is a command (it ends holds
      // and owed writes), and only those that fired before it was confirmed (F16, F18); a
      // user's write whose answer was lost is not (F40, F42: commanded after the stamp).
      const bool changed = c.adopt_prev_known && level != c.adopt_prev_level;
      const bool ends = c.adopt_is_command && changed && !(c.held && c.held_since > c.adopt_at);
      // The level before the write unknown (a client's write whose answer was lost came before
      // it): not known to have changed, so taken as found, and a hold stays (F27, stop 41).
      const bool unknown = c.adopt_is_command && !c.adopt_prev_known;
      Chan kept = c;
      c = Chan{};
      c.kept_changed_at = clock_.now();  // its kept timed command may go (model change 28)
      c.known = true;
      c.command = kept.adopt_is_command && !unknown;
      c.level = level;
      // F24: "found running" is as the node read it (this poll read the channel's PWM
      // registers), not the simulator's register when the poll ended (a run may end between).
      c.continuous = d == kLd && m.pwm_read_running[ch];
      c.at = clock_.now();
      c.deadline = kept.deadline;
      if (!ends) {
        c.held = kept.held;
        c.held_since = kept.held_since;
        c.disturbed_at = kept.disturbed_at;
        c.disturbed_poll_at = kept.disturbed_poll_at;
        c.owed = kept.owed;
        c.triggered = kept.triggered;
        c.trigger_at = kept.trigger_at;
      }
    }
  }
  if (!m.written_in_poll)
    for (int ch = 0; ch < kChannels; ++ch) {
      Chan& c = m.ch[ch];
      const bool registers_read = d != kLd || m.pwm_read_in_poll[ch] == m.poll_running;
      if (c.held && c.disturbed_at != TP{} && c.disturbed_poll_at == TP{} && registers_read)
        c.disturbed_poll_at = clock_.now();
    }
  if (!m.written_in_poll) m.found = true;
  // F11, F12: a device that answers again after being offline has restarted: on_restart's
  // writes computed from here on have that reason (found states included).
  if (m.unanswered) m.cause_at = clock_.now();
  m.unanswered = false;
  // Only a good poll shows the node what changed (F23): one with a write in it is not
  // compared.
  if (m.written_in_poll) return;
  m.prev_poll_at = m.last_poll_at;
  m.last_poll_at = clock_.now();
  m.polls_since_stale = std::min(m.polls_since_stale + 1, 1000);
}

void World::onWritten(const std::string& device, const std::vector<uint8_t>& chs,
                      const std::vector<bool>& sts) {
  const int d = devOf(device);
  checkCoils(d, chs, sts, "a user's write");
  for (size_t i = 0; i < chs.size(); ++i) commanded(d, chs[i], sts[i]);
}

void World::checkCoils(int d, const std::vector<uint8_t>& chs, const std::vector<bool>& sts,
                       const std::string& what) {
  // I1: reported done means the device shows it now. Not after the node took a repeated or
  // late frame as a read of this device (F90): a PWM run it missed may drive the channel.
  if (staleReadShows(d)) return;
  for (size_t i = 0; i < chs.size(); ++i)
    if (checked("I1") && simCoil(d, chs[i]) != sts[i])
      fail("I1", std::string(kNames[d]) + " out" + std::to_string(chs[i]) + ": " + what +
                     " was confirmed (" + (sts[i] ? "on" : "off") + ") but the device shows " +
                     (sts[i] ? "off" : "on"));
}

void World::takeFoundAfterRestart(int d, const FailsafeReport& r) {
  // F13, F25 (model change 19): after a restart, a changed channel that on_restart does not
  // write back (leave; safe on a channel whose safe state is hold) and that owes no safe write
  // has the level the poll that saw the restart showed as its intent, as found: a later poll or
  // a client's stop is compared with that level, not with the one the power cycle dropped.
  const bool restore = onRestart(d) == OnRestart::kRestore;
  const auto& outputs = node_->unit(r.device)->device().outputs();
  if (restore || outputs.size() < kChannels) return;
  const auto names_at = r.reason.find("outputs ");
  const auto names_end = r.reason.find(" changed with no command");
  // The channels the report names as changed; a device that answers again names none: those
  // whose level differs from what the model expects.
  const bool names = names_at != std::string::npos && names_end != std::string::npos;
  for (int ch = 0; ch < kChannels; ++ch) {
    Chan& c = model_[d].ch[ch];
    if (c.owed || (onRestart(d) == OnRestart::kSafe && hasSafe(d, ch))) continue;
    bool level = false;
    const bool changed = names ? r.reason.find("out" + std::to_string(ch), names_at) < names_end
                               : expected(c, clock_.now(), &level) && level != outputs[ch];
    if (!c.known || c.adopt || !changed) continue;
    Chan kept = c;
    c = Chan{};
    c.kept_changed_at = clock_.now();  // its kept timed command may go (model change 28)
    c.known = true;
    c.level = outputs[ch];
    c.at = clock_.now();
    c.deadline = kept.deadline;
    c.held = kept.held;
    c.held_since = kept.held_since;
    c.queued_at_hold = kept.queued_at_hold;
    c.triggered = kept.triggered;
    c.trigger_at = kept.trigger_at;
    c.shown_otherwise = kept.shown_otherwise;
    c.run_stop_unseen = kept.run_stop_unseen;
    c.run_stopped_at = kept.run_stopped_at;
    c.saved_run_unseen = kept.saved_run_unseen;
    c.saved_stop_read_at = kept.saved_stop_read_at;
  }
}

void World::onReport(const FailsafeReport& r) {
  for (int d = 0; d < kDevices; ++d)
    if (r.device == kNames[d])
      cover(std::string("report ") + triggerName(r.trigger) + " " + kTypes[d] + " " +
            actionName(r.action) + (r.confirmed ? "" : " (unconfirmed)"));
  if (trace_) std::fprintf(trace_, "report %s: %s\n", r.device.c_str(), r.text().c_str());
  const int d = devOf(r.device);
  if (d == kGen) return onGenericReport(r);
  DevModel& m = model_[d];
  const TP now = clock_.now();
  std::vector<int> chs;
  chs.reserve(r.channels.size());
  for (const std::string& name : r.channels) chs.push_back(name[3] - '0');  // out0..out7
  if (r.trigger == Trigger::kRestart) {
    // I6 (F11, F49, F28, F32, F34, F35): the outputs changed only if something changed them. A
    // change in the window of a justified one (a flash's end) may be seen by any later poll: only a
    // good poll after the window that showed nothing closes it (the port may be lost meanwhile). A
    // continuous run of the node's that a power cycle stopped shows at the poll that reads its
    // registers, up to 8 polls later (docs "Restart detection needs polls").
    bool run_stopped = false;
    const auto names_at = r.reason.find("outputs ");
    const auto names_end = r.reason.find(" changed with no command");
    if (names_at != std::string::npos && names_end != std::string::npos)
      for (int ch = 0; ch < kChannels; ++ch) {
        const std::string name = "out" + std::to_string(ch);
        const auto at = r.reason.find(name, names_at);
        if (at == std::string::npos || at > names_end) continue;
        Chan& named = m.ch[ch];
        run_stopped = run_stopped || named.run_stop_unseen || named.saved_run_unseen;
        named.run_stop_unseen = false;
        if (named.saved_stop_read_at != TP{}) named.saved_run_unseen = false;
      }
    if (r.reason.find("changed with no command") != std::string::npos && checked("I6") &&
        !m.justified && m.prev_poll_at >= m.justified_until && !run_stopped && !staleReadShows(d))
      fail("I6", std::string(kNames[d]) + ": restart reported (" + r.reason +
                     ") though nothing changed its outputs without a confirmed command");
    // F11, F44: the restart is what the poll that saw it showed; on_restart's writes may
    // change what was commanded before that poll (an I6-justified report: a PWM run that a
    // power-down save restarted shows as a change polls later).
    if (r.reason.find("changed with no command") != std::string::npos)
      m.cause_at = std::max(m.cause_at.value_or(TP{}), m.last_poll_at);
    // The report answers what a poll showed: a change made after that poll (the report's own
    // write heard but its answer lost) is still to be seen, and so is one whose write back was
    // not confirmed (the next poll shows the same change again).
    if (m.justified_at <= m.last_poll_at && r.confirmed) m.justified = false;
    // Its write not confirmed (its answer or its read back lost or refused): a write whose
    // answer was lost, for I6 (model change 30), as for the triggers' writes below.
    if (!r.levels_confirmed && !chs.empty()) {
      m.justified = true;
      m.justified_at = now;
    }
    m.cause_pending = false;
    takeFoundAfterRestart(d, r);
  }
  if (r.action == Action::kSafe) {
    // I11 (F1): "Nothing changes unless it is configured: the default safe state is hold".
    for (size_t i = 0; i < chs.size(); ++i)
      if (checked("I11") && !hasSafe(d, chs[i]))
        fail("I11", std::string(kNames[d]) + " out" + std::to_string(chs[i]) +
                        " (safe state hold) is written by a safe write (" + triggerName(r.trigger) +
                        ")");
  }
  // A restore's entries that started a continuous PWM run again (FailsafeReport::runs), and
  // whether it wrote plain levels too.
  auto isRun = [&r](size_t i) { return i < r.runs.size() && r.runs[i]; };
  bool plain = false;
  for (size_t i = 0; i < chs.size(); ++i) plain = plain || !isRun(i);
  if (r.action == Action::kRestore) {
    // I5 (F36-F39): what a restore writes, channel by channel.
    std::vector<bool> written(kChannels, false);
    for (const int ch : chs) written[ch] = true;
    // F37: a run the read just before the restore found, on a channel it leaves, is the
    // device's from then on, whatever became of the restore's own write (a read before it that
    // failed, or took another request's frame): the node decided that when the read answered.
    // Only when the read before answered: then the restore names channels, or is confirmed.
    if (d == kLd && (r.confirmed || !chs.empty()))
      for (int ch = 0; ch < kChannels; ++ch) {
        Chan& c = m.ch[ch];
        if (!written[ch] && m.run_read_in_op[ch] && c.runMayBeDevices(now) && c.known && !c.adopt)
          c.continuous = true;
      }
    for (size_t i = 0; i < chs.size(); ++i) {
      const int ch = chs[i];
      written[ch] = true;
      const Chan& c = m.ch[ch];
      const std::string name = std::string(kNames[d]) + " out" + std::to_string(ch);
      const bool v = r.states[i];
      if (i < r.runs.size() && r.runs[i]) {
        // docs "What restore writes": the node's continuous run (its write checked as it went
        // out), read stopped just before, on a channel neither held nor owed.
        if (d != kLd || m.run_read_at_start[ch])
          fail("I5", name +
                         ": the restore starts a PWM run again that the read just before "
                         "showed running");
        if ((c.held || c.owed) && hasSafe(d, ch))
          fail("I5", name + " is " + (c.held ? "held" : "owed") +
                         " safe but the restore starts its PWM run again");
        continue;
      }
      if ((c.held || c.owed) && hasSafe(d, ch)) {
        if (v != safeLevel(d, ch))
          fail("I5", name + " is " + (c.held ? "held" : "owed") + " safe but the restore writes " +
                         (v ? "on" : "off"));
        continue;
      }
      if (!c.known || c.adopt) continue;
      if (c.continuous) {
        fail("I5", name +
                       " runs a continuous PWM, which a restore does not restart, but the "
                       "restore writes it " +
                       std::string(v ? "on" : "off"));
        continue;
      }
      if (v != c.level)
        fail("I5", name + ": the restore writes " + (v ? "on" : "off") + " where the " +
                       (c.timed ? "timed command's final level" : "intent") + " is " +
                       (c.level ? "on" : "off"));
    }
    for (int ch = 0; ch < kChannels; ++ch) {
      const Chan& c = m.ch[ch];
      // F37: a channel the device runs a PWM on that is no timed command of the node's is
      // the device's: the restore leaves it (as the node read it just before the restore).
      const bool devices_run = d == kLd && c.runMayBeDevices(now) &&
                               (chs.empty() ? m.pwm_read_running[ch] : m.pwm_read_at_write[ch]);
      // A restore that wrote nothing and failed (its read before failed) is done again later.
      if (!r.confirmed && chs.empty()) break;
      // F90: what it restores was read from another's frame (a PWM run read on the wrong
      // channel): until the next poll reads it again.
      if (staleReadShows(d)) break;
      if (!written[ch] && c.known && !c.adopt && !c.continuous && !c.maybe_devices && !devices_run)
        fail("I5", std::string(kNames[d]) + " out" + std::to_string(ch) +
                       ": the restore leaves "
                       "it out, though its intent (" +
                       (c.level ? "on" : "off") + ") is known");
      // docs "What restore writes": the node's continuous run that the read just before showed
      // stopped is started again.
      const bool read_running = plain ? m.pwm_read_at_write[ch] : m.pwm_read_running[ch];
      // Not confirmed (a read before it failed): the runs it did not start go at the next one.
      if (!written[ch] && d == kLd && r.confirmed && c.known && !c.adopt && !c.node_run.empty() &&
          !read_running && !((c.held || c.owed) && hasSafe(d, ch)))
        fail("I5", std::string(kNames[d]) + " out" + std::to_string(ch) +
                       ": the restore leaves out the continuous PWM run the node started, "
                       "though the read just before showed it stopped");
      // F37: a run the read before the restore found stays the device's afterwards.
      if (!written[ch] && devices_run && m.ch[ch].known && !m.ch[ch].adopt)
        m.ch[ch].continuous = true;
    }
  }
  for (size_t i = 0; i < chs.size(); ++i) {
    if (!isRun(i)) continue;
    // A continuous run started again: the node's again (docs "What restore writes"), as the
    // device shows it (I1); one not confirmed leaves the channel unknown until a poll reads it.
    const int ch = chs[i];
    const std::string name = std::string(kNames[d]) + " out" + std::to_string(ch);
    const std::vector<uint16_t> run = m.ch[ch].node_run;
    if (r.runs_failed.find(name.substr(4) + ":") != std::string::npos || run.size() != 3) {
      lostAnswer(kLd, ch, 0);
      continue;
    }
    for (uint16_t k = 0; k < 3; ++k)
      if (simRegister(kLd, static_cast<uint16_t>(ch * 0x10 + k)) != run[k])
        fail("I1", name + ": its PWM run was reported started again, but register " +
                       std::to_string(ch * 0x10 + k) + " reads " +
                       std::to_string(simRegister(kLd, static_cast<uint16_t>(ch * 0x10 + k))));
    commandedTimed(kLd, ch, std::nullopt, false, -1.0, run);
    m.ch[ch].command = false;
  }
  if (r.levels_confirmed) {
    // F21: a restore or a safe write is a command like any other (not a hold's end).
    for (size_t i = 0; i < chs.size(); ++i) {
      if (isRun(i)) continue;
      Chan& c = m.ch[chs[i]];
      const bool held = c.held, triggered = c.triggered;
      const TP held_since = c.held_since, trigger_at = c.trigger_at;
      const auto deadline = c.deadline;
      c = Chan{};
      c.known = true;
      c.level = r.states[i];
      c.at = now;
      // The write ended any timed command the node kept for the next node (model change 28).
      c.kept_changed_at = now;
      c.held = held;
      c.held_since = held_since;
      c.triggered = triggered;
      c.trigger_at = trigger_at;
      c.deadline = deadline;
    }
  } else if (r.trigger != Trigger::kRestart) {  // heartbeat, command_timeout, start, shutdown
    // Not confirmed (its answer or its read back lost, or garbled): it may have been done, a
    // change the node did not confirm (I6's "a write whose reply was lost"; model change 30).
    if (!chs.empty()) {
      m.justified = true;
      m.justified_at = now;
    }
    // F40, F41: owed on the channels it carried; the stop's too (its "safe write that
    // fails" row names no trigger: the stop reads such a device after the others' safe writes
    // and writes it again when it answers; model change 29).
    for (int ch : chs) m.ch[ch].owed = true;
  }
}

void World::onGenericReport(const FailsafeReport& r) {
  DevModel& m = model_[kGen];
  // A port that is not open refuses the write unsent: the device was not asked.
  if (!link_.connected()) m.gen_unanswered = true;
  // I8 (F71): a value refused is reported, not retried: a "restart" write comes only
  // when the device did not answer the write before.
  if (r.trigger == Trigger::kRestart && checked("I8") && !m.gen_prev_silent)
    fail("I8", std::string("drive: safe values written again (") + r.reason +
                   ") though the device answered the previous safe write");
  // F72: a signal set since the trigger is not written. An owed write's trigger fired
  // before the previous report, so a signal it writes was not set since that report. A
  // trigger's own write leaves out only a signal set since it was last written safe (an owed
  // write carries only what the device did not get).
  const auto& signals = config_.devices[kGen].generic.signals;
  std::vector<bool> listed(signals.size(), false);
  for (size_t i = 0; i < signals.size(); ++i) {
    listed[i] =
        std::find(r.channels.begin(), r.channels.end(), signals[i].name) != r.channels.end();
    if (!signals[i].safe_value || i >= m.gen_set_at.size()) continue;
    if (listed[i] && r.trigger == Trigger::kRestart && m.gen_set_at[i] > m.gen_report_at)
      fail("I8", "drive: the owed safe write (restart) wrote " + signals[i].name +
                     ", set since its trigger fired");
    if (!listed[i] && r.trigger != Trigger::kRestart && m.gen_set_at[i] <= m.gen_written_at[i])
      fail("I8", std::string("drive: the safe write (") + triggerName(r.trigger) + ") left " +
                     signals[i].name + " out, not set since it was last written safe");
    if (listed[i]) m.gen_written_at[i] = clock_.now();
  }
  m.gen_report_at = clock_.now();
  // A device that answered throughout has the safe values it keeps, the refused one aside.
  if (!m.gen_unanswered && !port_lost_) {
    for (size_t i = 0; i < signals.size(); ++i) {
      const SignalConfig& s = signals[i];
      if (!s.safe_value || !listed[i]) continue;
      if (config_.generic_refuses && s.address == 0x20) continue;
      if (m.gen_refused.count(s.address)) continue;  // refused now: reported, not retried
      uint16_t raw = 0;
      const Table t = s.table;
      sim(kGen)->read(t, s.address, clock_.now(), &raw);
      std::vector<uint16_t> words;
      writeValueProblem(s, *s.safe_value, &words);
      if (words.empty() || raw != words[0])
        fail("I8", "drive: " + s.name + " is " + std::to_string(raw) + " (raw) after the safe " +
                       "write (" + triggerName(r.trigger) + "), not its safe value " +
                       std::to_string(*s.safe_value));
    }
  }
  m.gen_prev_silent = m.gen_unanswered;
  m.gen_unanswered = false;
  m.gen_refused.clear();
}

// I2 (F6-F9, F16, F87): a held channel of a device that answers shows its safe state
// within the deadline timer's period, one transaction in progress (a silent device's, with its
// retries) and a few transactions per device (a write and its read back, an LD58A08's PWM
// reads): the docs' "timeout plus that tenth plus one bus transaction for each output write".
void World::checkHeld() {
  if (!node_ || !node_->started() || port_lost_) return;
  const TP now = clock_.now();
  // The timer's period, the transaction in progress (a silent device's, with its retries), one
  // transaction for each output write queued ahead (F87-F89; a silent device's is one
  // with its retries, an answering LD58A08's a few: its PWM reads, the write, its read back),
  // and the safe writes of each device.
  // The node's own stated bound (BusRuntime::safeAfterTrigger, docs/failsafe.md "How long until
  // safe"), with the writes actually queued ahead.
  const auto budget = [this](size_t queued) {
    return node_->safeAfterTrigger(queued).afterTrigger();
  };
  for (int d = 0; d < kGen; ++d) {
    DevModel& m = model_[d];
    const MemoryLinkFaults& f = link_.faults(kAddr[d]);
    if (f.silent || f.lost || f.late || f.garbled || f.refused || f.foreign) continue;
    // An owed write goes when the device answers a poll again, behind what is queued then.
    if (now >= m.reachable_since && !m.queued_noted) {
      m.queued_at_reachable = node_->queuedJobs();
      m.queued_noted = true;
    }
    // F41 "as soon as the device answers a poll again": that poll's own transactions come
    // first (an LD58A08's first poll after it answers reads every channel's PWM registers, then
    // the coils: 9; model change 27).
    const double poll_transactions = d == kLd ? 9 : 2;
    const double one_poll = poll_transactions * node_->safeAfterTrigger(0).answered_transaction;
    if (now - m.reachable_since < dur(budget(m.queued_at_reachable) + pollPeriod(d) + one_poll))
      continue;
    for (int ch = 0; ch < kChannels; ++ch) {
      const Chan& c = m.ch[ch];
      // Disturbed since it was held (a write nobody confirmed): from the good poll that found
      // it (polls wait behind the writes queued meanwhile).
      if (c.held && c.disturbed_at != TP{} && c.disturbed_poll_at == TP{}) continue;
      const TP from = std::max(c.held_since, c.disturbed_poll_at);
      if (!c.held || now - from < dur(budget(c.queued_at_hold))) continue;
      if (checked("I2") && simCoil(d, ch) != safeLevel(d, ch))
        fail("I2", std::string(kNames[d]) + " out" + std::to_string(ch) + " is held safe (" +
                       safeStateName(safeOf(d, ch)) +
                       ") since t=" + std::to_string(secs(c.held_since - start_)) +
                       " (on_restart: " + onRestartName(onRestart(d)) +
                       ") but the device, answering since t=" +
                       std::to_string(secs(m.reachable_since - start_)) + ", shows it " +
                       (simCoil(d, ch) ? "on" : "off"));
    }
    // I5 (docs "What restore writes", "Restart detection needs polls"; #32 item 7): with
    // on_restart: restore, the node's continuous run a power cycle stopped runs again once the
    // device answers: the poll that reads its registers (one channel a poll, so within 8 polls)
    // sees the restart, and the restore starts it. Not on a channel held or owed safe.
    if (d != kLd || onRestart(d) != OnRestart::kRestore) continue;
    for (int ch = 0; ch < kChannels; ++ch) {
      const Chan& c = m.ch[ch];
      if (!c.run_stop_unseen || c.node_run.empty() || !c.known || c.adopt || c.held || c.owed)
        continue;
      const TP from = std::max(c.run_stopped_at, m.reachable_since);
      if (now - from < dur(10 * pollPeriod(d) + 3.0 + budget(node_->queuedJobs()))) continue;
      if (simRegister(kLd, static_cast<uint16_t>(ch * 0x10 + 2)) != 0) continue;
      fail("I5", "pwm out" + std::to_string(ch) +
                     ": the continuous PWM run the node started, stopped by a power cycle at t=" +
                     std::to_string(secs(c.run_stopped_at - start_)) +
                     ", does not run again though the device answers since t=" +
                     std::to_string(secs(m.reachable_since - start_)) + " (on_restart: restore)");
    }
  }
}

}  // namespace simulation_world
}  // namespace modbus_rtu_driver
