// World: the model's inputs and every attempt on the line (I1, I6, I7, I21 at the frame).
#include "simulation_world.h"

namespace modbus_rtu_driver {
namespace simulation_world {

// ---- the model's inputs ------------------------------------------------------------------------

bool World::expected(const Chan& c, TP t, bool* level) const {
  if (!c.known || c.adopt || c.continuous) return false;
  if (c.timed) {
    const double slack = 0.5 + 0.02 * c.duration;  // F32
    if (std::abs(secs(t - c.ends)) <= slack) return false;
    if (t < c.ends) {
      if (!c.during) return false;
      *level = *c.during;
      return true;
    }
  }
  *level = c.level;
  return true;
}

void World::commanded(int d, int ch, bool level) {
  if (model_[d].in_poll) model_[d].written_in_poll = true;
  Chan& c = model_[d].ch[ch];
  const auto deadline = c.deadline;  // only C/command moves the dead man (F9)
  c = Chan{};
  c.deadline = deadline;
  c.known = c.command = true;
  c.level = level;
  c.at = clock_.now();
  c.kept_changed_at = c.at;
  // F18: a confirmed command ends the hold and cancels what was owed; a trigger before
  // it no longer covers it.
}

void World::commandedTimed(int d, int ch, std::optional<bool> during, bool after, double seconds,
                           const std::vector<uint16_t>& run) {
  commanded(d, ch, after);
  Chan& c = model_[d].ch[ch];
  if (seconds < 0) {
    c.continuous = true;
    c.node_run = run;
    // F31: a continuous run the device confirmed counts as read running until a read.
    if (d == kLd) model_[d].pwm_read_running[ch] = true;
    return;
  }
  c.timed = true;
  c.settled = false;
  c.during = during;
  c.duration = seconds;
  c.ends = c.ends_earliest = clock_.now() + dur(seconds);
}

void World::unconfirmed(int d, int ch, double not_before_s, bool as_command) {
  model_[d].ch[ch].kept_changed_at = clock_.now();  // a timed command it may replace is dropped
  // The docs do not say what the intent is after a write whose answer was lost: nothing is
  // checked on the channel until a poll shows it again.
  Chan& c = model_[d].ch[ch];
  c.adopt_prev_known = expected(c, clock_.now(), &c.adopt_prev_level);
  // F27: on a held channel a poll showed otherwise, the level before is what it showed.
  if (as_command && c.held && c.shown_otherwise) {
    c.adopt_prev_known = true;
    c.adopt_prev_level = !safeLevel(d, ch);
  }
  if (c.held) {
    c.disturbed_at = clock_.now();
    c.disturbed_poll_at = TP{};
  }
  if (model_[d].in_poll) model_[d].written_in_poll = true;
  c.adopt_at = clock_.now();
  c.known = false;
  c.adopt = true;
  c.adopt_is_command = as_command;
  c.adopt_after_poll = model_[d].polls_started;
  c.adopt_not_before = clock_.now() + dur(not_before_s);
}

void World::lostAnswer(int d, int ch, double seconds) {
  const Chan& c = model_[d].ch[ch];
  const TP now = clock_.now();
  // Counted from now, when the caller learns the answer was lost, as the node counts it: the
  // device, if it heard the write, started it before now and so ends it before the window does.
  TP until = seconds > 0 ? now + dur(seconds + 0.5 + 0.02 * seconds) : now;
  // F32: the end counts from when the device confirmed the command, as the node counts it (an
  // LD58A08 run's job ends later, after its read back: c.ends; model change 33).
  if (c.known && c.timed && !c.settled) {
    const TP end = c.ends_earliest != TP{} ? c.ends_earliest : c.ends;
    until = std::max(until, end + dur(0.5 + 0.02 * c.duration));
  }
  // F46 "also when another write whose answer was lost came between": a timed command
  // that earlier lost write may have started (or left running) still decides (model change 14).
  if (c.adopt) until = std::max(until, c.adopt_not_before);
  unconfirmed(d, ch, secs(until - now), false);
}

void World::lostPwmRun(int ch, double seconds) {
  lostAnswer(kLd, ch, std::max(seconds, 0.0));
  // F31: the device may have started it; a client's coil write over it keeps it going.
  DevModel& m = model_[kLd];
  if (seconds < 0)
    m.lost_run_for_good[ch] = true;
  else
    m.lost_run_until[ch] =
        std::max(m.lost_run_until[ch], clock_.now() + dur(seconds + 0.5 + 0.02 * seconds));
}

void World::deviceDisturbed(int d, bool justified, double extra) {
  DevModel& m = model_[d];
  m.cause_at = clock_.now();
  m.cause_pending = true;
  // A device that stopped answering is probed again with backoff, up to backoff_max (5 s,
  // bus_scheduler.h); an owed write goes when it answers a poll again (F41).
  m.reachable_since = std::max(m.reachable_since, clock_.now() + dur(5.0 + extra));
  m.queued_noted = false;
  if (justified) {
    m.justified = true;
    m.justified_at = clock_.now();
  }
}

void World::onAttempt(const LineEvent& e) {
  if (e.port_failed) {
    // The adapter failed with this request out: as a lost port (below, the request's device
    // heard it and its answer is lost).
    port_lost_ = true;
    killed_frame_out_ = true;
    for (int dev = 0; dev < kDevices; ++dev) deviceDisturbed(dev, false);
  }
  // Incorrect sequence, repetition: the node read a frame that was not this request's reply
  // (a late or repeated one, or a foreign frame), and took it or rejected it.
  if (e.stale) cover(e.answered ? "line another's reply taken" : "line another's reply rejected");
  if (e.taken_by_same_read) cover("path a new read took its frame's late reply within the guard");
  // I22 (docs/share.md): a client's read, also one cut short in another device's guard and
  // retried after the guarded request, gets 1 + retries attempts at most.
  if (node_) {
    const auto read = share_read_attempts_.find(node_->currentTag());
    if (read != share_read_attempts_.end() && checked("I22") &&
        ++read->second > 1 + config_.link.retries)
      fail("I22", "a share client's " + e.request.describe() + " got attempt " +
                      std::to_string(read->second) + " with retries " +
                      std::to_string(config_.link.retries));
  }
  const int d = devOf(e.request.slave);
  if (d < 0) return;
  // A repeated or late reply of the same shape, taken as this read's (Modbus RTU has no
  // transaction number: failsafe.md F-rule "Replies the line repeats or delays"): the node read
  // outputs that are not the device's now, and a change it reports from them has a cause.
  if (e.stale && e.answered) {  // a read's reply, or a write's echo (an earlier identical one)
    DevModel& m = model_[d];
    m.polls_since_stale = 0;
    m.stale_read_at = clock_.now();
    if (d == kLd && e.request.function == FunctionCode::kReadHoldingRegisters &&
        e.request.address % 0x10 == 0 && e.request.address / 0x10 < kChannels &&
        e.request.count == 3)
      m.stale_pwm_unread[e.request.address / 0x10] = true;
    // A safe write that read its channels from that frame (an LD58A08's PWM registers) may fail
    // its read back and be owed (F40): written when the device answers a poll again, behind
    // what is queued then (F41), as after a refusal (model change 34, I2).
    m.reachable_since = std::max(m.reachable_since, clock_.now());
    m.queued_noted = false;
    // What it took as found may also hide a timed command's end: until it ends (and its slack).
    for (const Chan& c : m.ch)
      if (c.timed && !c.continuous)
        m.justified_until =
            std::max(m.justified_until, c.ends + dur(0.5 + 0.02 * c.duration) + dur(2.0));
  }
  // I21 (F90): within late_reply_guard of its request's time-out, a late reply is never taken
  // as another request's.
  if (e.stale && e.answered && checked("I21") && e.taken_within_guard)
    fail("I21", std::string(kNames[d]) + ": " + e.request.describe() +
                    " took a late reply to another request, within late_reply_guard (" +
                    std::to_string(config_.link.late_reply_guard) + " s) of its time-out");
  if (e.refused) {  // an exception the fault injected: the device did nothing
    if (d == kGen && !isReadFunction(e.request.function))
      model_[kGen].gen_refused.insert(e.request.address);
    // docs "What happens when", a safe write that fails: a refused one (its write, or the read
    // an LD58A08's safe write needs first) is owed like one that got no reply, written when the
    // device answers a poll again. Nothing changed on the device (no cause of a restart): only
    // the time it counts as reachable moves.
    DevModel& m = model_[d];
    m.reachable_since = std::max(m.reachable_since, clock_.now());
    m.queued_noted = false;
    return;
  }
  DevModel& m = model_[d];
  const bool write = !isReadFunction(e.request.function);
  if (d == kLd && e.answered && e.request.function == FunctionCode::kReadHoldingRegisters &&
      e.request.address % 0x10 == 0 && e.request.address / 0x10 < kChannels &&
      e.request.count == 3) {
    const int ch = e.request.address / 0x10;
    const bool runs = e.values.size() == 3 && e.values[2] != 0;  // as the node read it
    m.pwm_read_running[ch] = runs;
    if (m.in_poll && !e.stale) m.stale_pwm_unread[ch] = false;  // read again (F90)
    if (!runs) {  // F31: a read that shows the run ended ends what a lost PWM write left
      m.lost_run_until[ch] = TP{};
      m.lost_run_for_good[ch] = false;
    }
    // Read by a poll: running, the node's (or the device's, F77) from now on; a saved
    // run read stopped, its end is seen by this poll.
    if (m.in_poll && node_ && node_->currentTag() == 0) {
      Chan& read = m.ch[ch];
      if (runs) read.run_stop_unseen = read.saved_run_unseen = false;
      if (!runs && read.saved_run_unseen && read.saved_stop_read_at == TP{})
        read.saved_stop_read_at = e.at;
    }
    m.pwm_read_in_poll[ch] = m.poll_running;
    // F37 and "Restart detection needs polls": a run a poll reads that is no timed
    // command of the node's still running makes the channel the device's until a plain write,
    // also after the run ended: not compared, not restored.
    Chan& c = m.ch[ch];
    // Only a poll's read or a fail-safe write's read back on a channel it left (F37, F79):
    // not a command's read back, and not the reads before the fail-safe's own write (the read
    // just before a restore counts at its report, below).
    const bool fs_op = node_ && node_->currentTag() == 0;
    const bool readback = fs_op && m.readback_pending && !m.fs_written[ch];
    if (fs_op && m.readback_pending) {
      m.readback_pending = false;
      m.fs_written.assign(kChannels, false);
    }
    if (fs_op && !m.in_poll && !readback) m.run_read_in_op[ch] = runs;
    if (runs && c.known && !c.adopt && ((m.in_poll && fs_op) || readback)) {
      // Either may be right: read from another request's frame (F90: the node may take the run
      // as the device's, or, if the poll failed there, not at all; the next poll that reads it
      // decides), or near the end of the node's own run (the node may count it ended: its end
      // runs from when the write went out, the model's from the confirmation, up to a
      // transaction and a read back later).
      if (e.stale || (c.nodeRuns(e.at) && e.at + dur(1.0) >= c.ends))
        c.maybe_devices = true;
      else if (!c.nodeRuns(e.at))
        c.continuous = true;
    }
  }
  if (d == kLd && e.heard && e.request.function == FunctionCode::kWriteMultipleRegisters &&
      e.request.address % 0x10 == 0 && e.request.address / 0x10 < kChannels)
    m.pwm_heard[e.request.address / 0x10] = e.at;
  if (d == kLc && e.heard && e.request.function == FunctionCode::kWriteMultipleRegisters &&
      e.request.count == 2 && e.request.address % 5 == 3 && e.request.address / 5 < kChannels)
    m.flash_heard[e.request.address / 5] = e.at;
  // When the LC board confirmed a flash (its mode and delay registers, 3 + 5 n): when its answer
  // has come (F32), now, not when the request went out (e.at; model change 18).
  if (d == kLc && e.answered && e.request.function == FunctionCode::kWriteMultipleRegisters &&
      e.request.count == 2 && e.request.address % 5 == 3 && e.request.address / 5 < kChannels)
    m.flash_answered[e.request.address / 5] = clock_.now();
  // When the device confirmed a PWM write: its answer, or (answer lost) the read that confirmed
  // it (Ld58a08::confirmPwm reads the channel back); as for a flash, when that answer has come.
  if (d == kLd && write && e.request.function == FunctionCode::kWriteMultipleRegisters &&
      e.request.values.size() == 3 && e.request.address % 0x10 == 0 &&
      e.request.address / 0x10 < kChannels) {
    const int ch = e.request.address / 0x10;
    if (node_ && node_->currentTag() == 0) {
      // The fail-safe's own PWM write: a restore starting a continuous run again, as it was
      // written (docs "What restore writes").
      m.run_read_at_start[ch] = m.pwm_read_running[ch];
      const Chan& c = m.ch[ch];
      if (checked("I5") && (c.node_run.empty() || e.request.values != c.node_run))
        fail("I5", "pwm out" + std::to_string(ch) + ": the fail-safe writes " +
                       e.request.describe() +
                       (c.node_run.empty() ? ", which is no continuous run the node started"
                                           : ", not the run as the node started it"));
    }
    m.pwm_write_answered[ch] = e.answered ? clock_.now() : TP{};
    m.pwm_confirm_pending[ch] = !e.answered;
  }
  if (d == kLd && e.answered && e.request.function == FunctionCode::kReadHoldingRegisters &&
      e.request.address % 0x10 == 0 && e.request.address / 0x10 < kChannels &&
      m.pwm_confirm_pending[e.request.address / 0x10]) {
    m.pwm_write_answered[e.request.address / 0x10] = clock_.now();
    m.pwm_confirm_pending[e.request.address / 0x10] = false;
  }
  // F29, F31: a stop the device confirmed (an enable register written 0: the node's own before
  // a plain write, or a client's it carried) ends what the node read of that channel's run.
  if (d == kLd && e.answered && write &&
      (e.request.function == FunctionCode::kWriteSingleRegister ||
       e.request.function == FunctionCode::kWriteMultipleRegisters))
    for (size_t i = 0; i < e.request.values.size(); ++i) {
      const auto reg = static_cast<uint16_t>(e.request.address + i);
      if (reg % 0x10 == 2 && reg / 0x10 < kChannels && e.request.values[i] == 0) {
        m.pwm_read_running[reg / 0x10] = false;
        m.lost_run_until[reg / 0x10] = TP{};
        m.lost_run_for_good[reg / 0x10] = false;
        m.stop_answered[reg / 0x10] = clock_.now();
      }
    }
  if (!e.answered) {
    m.unanswered = true;
    // A device that does not answer may be taken offline: its return is a restart (F11).
    // A write it heard but whose answer was lost changed outputs the node did not confirm.
    deviceDisturbed(d, write && e.heard);
    // A flash or PWM run it started changes the outputs again at its end (F86).
    if (write && e.heard && sim(d)->startsSomething(e.request))
      m.justified_until = std::max(m.justified_until, e.at + dur(8.0));
    // It may also have replaced a running timed command (a coil write over a flash): the change
    // then shows at that command's end, after the first report (F32's slack, a late poll).
    if (write && e.heard)
      for (const Chan& c : m.ch)
        if (c.timed && !c.continuous)
          m.justified_until =
              std::max(m.justified_until, c.ends + dur(0.5 + 0.02 * c.duration + 2.0));
    if (d == kGen) m.gen_unanswered = true;
  }
  // I7: a write that starts something reaches the device once per transaction.
  if (e.heard && sim(d)->startsSomething(e.request) && checked("I7") &&
      ++starts_by_transaction_[e.execute_id] > 1)
    fail("I7", std::string(kNames[d]) + ": " + e.request.describe() +
                   " reached the device twice in one transaction");
  if (d == kGen || !write || !node_) return;
  const bool coils = e.request.function == FunctionCode::kWriteSingleCoil ||
                     e.request.function == FunctionCode::kWriteMultipleCoils;
  if (!coils || node_->currentTag() != 0) return;
  m.pwm_read_at_write = m.pwm_read_running;
  // Its read back follows (a poll of the device: one channel's PWM registers, then the coils).
  if (e.answered) {
    m.readback_pending = true;
    for (size_t i = 0; i < e.request.values.size(); ++i)
      if (e.request.address + i < kChannels) m.fs_written[e.request.address + i] = true;
  }
  // A write of the fail-safe's own (no command's job runs): I3 and I4.
  for (size_t i = 0; i < e.request.values.size(); ++i) {
    const int ch = e.request.address + static_cast<int>(i);
    if (ch >= kChannels) continue;
    const bool v = e.request.values[i] != 0;
    const Chan& c = m.ch[ch];
    const std::string name = std::string(kNames[d]) + " out" + std::to_string(ch);
    if (c.held) {
      if (checked("I3") && v != safeLevel(d, ch))
        fail("I3", name + " is held safe (" + safeStateName(safeOf(d, ch)) +
                       ") but a fail-safe write sets it " + (v ? "on" : "off"));
      continue;
    }
    if (c.owed && hasSafe(d, ch) && v == safeLevel(d, ch)) continue;
    bool level = false;
    if (!expected(c, e.at, &level)) continue;
    checked("I4");  // a write on a channel whose intent is known
    if (level == v) continue;
    if (hasSafe(d, ch) && v == safeLevel(d, ch) && c.triggered && c.trigger_at >= c.at) continue;
    // F5, F61: the stop's safe writes run after what was queued before them, and they
    // are what the outputs are left with.
    if (stopping_ && hasSafe(d, ch) && v == safeLevel(d, ch)) continue;
    // The node sees a restart at a poll (F11): a command confirmed before the poll that saw
    // it is not newer than the restart; one confirmed after it is (F44).
    // A change the device made by itself that I6 accepts (a power cycle, a lost answer's write,
    // a flash or saved PWM run ending) may be seen at any poll of its window: what that poll
    // saw is a restart for the commands confirmed before it.
    // So may a node's continuous run a power cycle stopped, which the poll that reads its
    // registers reports, up to 8 polls after the power cycle (docs "Restart detection needs
    // polls"; model change 13).
    const bool run_stop_seeable = std::any_of(m.ch.begin(), m.ch.end(), [](const Chan& x) {
      return x.run_stop_unseen || x.saved_run_unseen;
    });
    // F90: a read that took another's frame, and the poll after it that reads the truth again,
    // may each show the node a change.
    const bool seeable = m.cause_pending || m.justified || e.at < m.justified_until ||
                         run_stop_seeable || staleReadShows(d);
    // F90: a read that took another's frame may show the node a change that is none; a
    // command confirmed before it is then older than the restart it reports.
    const bool stale_seen = staleReadShows(d) && c.at <= m.stale_read_at;
    if ((m.cause_at && *m.cause_at >= c.at) || (seeable && c.at <= m.last_poll_at) || stale_seen) {
      if (onRestart(d) == OnRestart::kSafe && hasSafe(d, ch) && v == safeLevel(d, ch)) continue;
      if (onRestart(d) == OnRestart::kRestore && c.timed && v == c.level) continue;
    }
    fail("I4", name + ": a fail-safe write sets it " + (v ? "on" : "off") + " where the " +
                   (c.command ? "confirmed command" : "intent") +
                   " of t=" + std::to_string(secs(c.at - start_)) + " says " +
                   (level ? "on" : "off") + " and nothing since is a reason");
  }
}

}  // namespace simulation_world
}  // namespace modbus_rtu_driver
