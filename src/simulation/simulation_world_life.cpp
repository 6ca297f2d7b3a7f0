// World: failures, time, the trigger clock and the node's life (start, stop, kill).
#include "simulation_world.h"

namespace modbus_rtu_driver {
namespace simulation_world {

void World::fail(const std::string& invariant, const std::string& message) {
  if (known_.count(invariant)) {
    if (known_hits_[invariant]++ == 0 && known_example_.empty())
      known_example_ = invariant + " at step " + std::to_string(step_index_) + ": " + message;
    return;
  }
  if (failure_) return;
  SimFailure f;
  f.step = step_index_;
  f.invariant = invariant;
  char when[32];
  std::snprintf(when, sizeof when, "t=%.3f: ", simSeconds());
  f.message = when + message;
  f.frames = link_.history();
  if (steps_) f.steps.assign(steps_->begin(), steps_->end());
  failure_ = f;
}

// ---- time --------------------------------------------------------------------------------------

void World::runFor(double seconds) {
  runUntil(clock_.now() + dur(seconds));
}

BusRuntime::AwaitWrites World::awaitOnClock() {
  return [this](const BusRuntime::Pending& writes, TP deadline) {
    runUntil(deadline, [&writes] { return BusRuntime::allDone(writes); });
  };
}

// Runs the bus, the deadline timer and the heartbeat's sender on one thread until `end` (or
// until `done`): whatever is due first runs first; time jumps to the next thing due.
void World::runUntil(TP end, const std::function<bool()>& done) {
  for (;;) {
    if (done && done()) return;
    const TP now = clock_.now();
    // The timer and the heartbeat's sender are other threads in the node: they run when due,
    // between two bus jobs (a job cannot be interrupted halfway).
    if (node_ && node_->started() && now >= next_feed_) {
      if (alive_) {
        node_->feedHeartbeat();
        last_feed_ = now;
        lost_ = false;
      }
      next_feed_ = now + dur(config_.heartbeat / 4);
    }
    if (node_ && node_->started() && now >= next_dev_feed_) {
      if (dev_alive_) {
        node_->feedDeviceHeartbeat(kNames[kLd]);
        dev_last_feed_ = now;
        dev_lost_ = false;
      }
      next_dev_feed_ = now + dur(config_.devices[kLd].failsafe.heartbeat_timeout / 4);
    }
    if (node_ && node_->started() && now >= next_tick_) {
      tick();
      next_tick_ = now + dur(node_->checkPeriod());
    }
    if (now >= end) return;
    TP next = TP::max();
    if (node_ && node_->scheduler().step(&next)) {
      // A shared request ran while another device's late-reply guard held the line.
      const uint64_t in_guards = node_->scheduler().ranInGuards();
      if (in_guards > ran_in_guards_) cover("path shared request in another device's guard");
      ran_in_guards_ = in_guards;  // a new node counts from 0
      // ... a read whose answer was lost there, its retries after the guarded request.
      const uint64_t cut = node_->scheduler().cutInGuards();
      if (cut > cut_in_guards_) cover("path a shared read's retries after the guarded request");
      cut_in_guards_ = cut;
      continue;
    }
    const TP t = std::min({next, next_tick_, next_feed_, next_dev_feed_, end});
    if (t > now) clock_.advanceTo(t);
  }
}

// The deadline timer: the model's triggers fire first (from the docs' rule), then the node's.
void World::tick() {
  const TP now = clock_.now();
  if (!lost_ && now - last_feed_ >= dur(config_.heartbeat)) {
    lost_ = true;  // F6, F7: no message within timeout; every device obeys the bus heartbeat
    for (int d = 0; d < kGen; ++d)
      for (int ch = 0; ch < kChannels; ++ch)
        if (hasSafe(d, ch)) hold(d, ch);
  }
  const FailsafeConfig& ld = config_.devices[kLd].failsafe;
  if (!ld.heartbeat_topic.empty() && !dev_lost_ &&
      now - dev_last_feed_ >= dur(ld.heartbeat_timeout)) {
    dev_lost_ = true;  // F7: that device's own heartbeat: its channels only
    for (int ch = 0; ch < kChannels; ++ch)
      if (hasSafe(kLd, ch)) hold(kLd, ch);
  }
  for (int d = 0; d < kGen; ++d)
    for (int ch = 0; ch < kChannels; ++ch) {
      Chan& c = model_[d].ch[ch];
      if (c.deadline && now >= *c.deadline) {  // F9
        c.deadline.reset();
        hold(d, ch);
      }
    }
  node_->checkDeadlines();
}

void World::hold(int d, int ch) {
  Chan& c = model_[d].ch[ch];
  const TP now = clock_.now();
  // F87: one transaction for each output write queued before the trigger.
  if (!c.held) {
    c.held_since = now;
    c.queued_at_hold = node_ ? node_->queuedJobs() : 0;
  }
  c.held = true;
  c.triggered = true;
  c.trigger_at = now;
}

// ---- the node's life -----------------------------------------------------------------------

void World::resetModelForNewNode() {
  const TP now = clock_.now();
  for (int d = 0; d < kDevices; ++d) {
    DevModel& m = model_[d];
    // A new node has read no PWM registers yet.
    std::fill(m.pwm_read_running.begin(), m.pwm_read_running.end(), false);
    std::fill(m.lost_run_until.begin(), m.lost_run_until.end(), TP{});
    std::fill(m.lost_run_for_good.begin(), m.lost_run_for_good.end(), false);
    // F80: a flash the killed node started cannot be told from a restart. A device
    // whose state the old node did not know may change by itself too.
    // Each of its flashes changes the outputs at its own end (F86): every report up to
    // the last end (+ the slack of F32) is justified, not only the first.
    bool running_unknown = false;
    for (size_t ch = 0; ch < m.ch.size(); ++ch) {
      Chan& c = m.ch[ch];
      if (!c.known && c.adopt) running_unknown = true;
      const TP seen_by = c.ends + dur(0.5 + 0.02 * c.duration);
      // An LD58A08 burst too: its last pulse may still be on while its registers read it ended.
      if (c.timed && !c.continuous && seen_by > now) {
        running_unknown = true;
        // The poll that sees it may come later: the bus busy with others, a retry.
        m.justified_until = std::max(m.justified_until, seen_by + dur(2.0));
      }
      c = Chan{};
      // Resumed as the previous node left it, not as a command of this node's (found).
      const std::optional<Chan>* carried = ch < carried_[d].size() ? &carried_[d][ch] : nullptr;
      // Its end as the node counts it (F32: from the device's answer) is up to a callback's
      // delay before the model's (ends_earliest, from the model's view of that answer, or from
      // the callback): near it the new node may or may not have resumed it (model change 36).
      const bool maybe_carried = carried && *carried && (*carried)->ends > now;
      if (maybe_carried && (*carried)->ends_earliest != TP{} &&
          (*carried)->ends_earliest <= now + dur(0.5)) {
        cover("fault kept timed command ends as the node starts");
        c.kept_uncertain = true;
        running_unknown = true;
        m.justified_until =
            std::max(m.justified_until,
                     (*carried)->ends + dur(0.5 + 0.02 * (*carried)->duration) + dur(2.0));
      } else if (maybe_carried) {
        const Chan& k = **carried;
        c.known = true;
        c.level = k.level;
        c.timed = k.timed;
        c.during = k.during;
        c.ends = k.ends;
        c.ends_earliest = k.ends_earliest;
        c.duration = k.duration;
        c.continuous = k.continuous;
        c.at = now;
        c.from_old_node = true;
        // From a list that had not caught up with the killed node: the device may no longer
        // run it (a write ended it), and its end may then show as a change (model change 28).
        if (k.kept_lagging) {
          cover("fault resumed from a list behind the killed node");
          running_unknown = true;
          m.justified_until =
              std::max(m.justified_until, k.ends + dur(0.5 + 0.02 * k.duration) + dur(2.0));
        }
      }
    }
    carried_[d].clear();
    if (running_unknown) {
      m.justified = true;
      m.justified_at = now;
    }
    m.found = false;
    m.reachable_since = std::max(m.reachable_since, now);
    m.queued_noted = false;
    m.gen_unanswered = false;
    m.gen_prev_silent = true;
  }
  lost_ = false;
}

void World::keepRunningTimed() {
  // What DeviceFailsafe's timed-changed callback last put on the parameter server: each channel
  // whose timed command runs (a known one, not ended). The server lags the node by
  // kept_latency (docs/failsafe.md, "A node started during a flash"): a change younger than that
  // may not have landed, and the next node reads the list as it is (model change 28).
  const TP now = clock_.now();
  const double now_s = kept_timed_.seconds();
  const auto& landed = kept_timed_.landed();
  for (int d = 0; d < kGen; ++d) {
    carried_[d].assign(kChannels, std::nullopt);
    std::vector<std::optional<KeptTimedCommand>> stored(kChannels);
    if (const auto it = landed.find(kNames[d]); it != landed.end())
      for (const KeptTimedCommand& k : it->second)
        if (k.channel < kChannels && k.ends > now_s) stored[k.channel] = k;
    for (int ch = 0; ch < kChannels; ++ch) {
      const Chan& c = model_[d].ch[ch];
      // Model change 23 (failsafe.md F80): only a timed command with an end; a run with
      // none is found by the next node.
      const bool runs = c.known && !c.adopt && !c.continuous && c.timed && c.ends > now;
      // Not landed yet: changed after the list that landed was kept, and within two writes
      // (one in flight, the newest waiting) of the kill. With no latency nothing is late: the
      // node's list must match the model's.
      const bool recent = config_.kept_latency > 0 &&
                          c.kept_changed_at > kept_timed_.landedKeptAt(kNames[d]) &&
                          now - c.kept_changed_at <= dur(2 * config_.kept_latency);
      if (!recent) {
        if (runs) carried_[d][ch] = c;
        continue;
      }
      // Not landed: the next node resumes the list as it is; a command missing from it ends as
      // a change the new node cannot place (resetModelForNewNode justifies it).
      if (!stored[ch]) continue;
      const KeptTimedCommand& k = *stored[ch];
      Chan x;
      x.known = x.timed = true;
      x.level = k.after;
      if (k.during >= 0) x.during = k.during == 1;
      x.ends = x.ends_earliest = now + dur(k.ends - now_s);
      x.duration = k.ends - now_s;
      x.at = now;
      x.kept_lagging = true;
      carried_[d][ch] = x;
    }
  }
}

void World::startNode() {
  if (node_) return;
  resetModelForNewNode();
  // The bus configuration the node parses from its YAML (BusConfig), drawn by the seed.
  BusConfig bus;
  bus.devices = config_.devices;
  if (config_.heartbeat > 0) {
    bus.heartbeat_topic = "/alive";
    bus.heartbeat_timeout = config_.heartbeat;
  }
  bus.shutdown_timeout = config_.shutdown_timeout;
  bus.allow_raw_writes = true;
  bus.share.enabled = true;
  // No sockets here (ShareGateway::open, forward). The broadcast turnaround is a sleep on the
  // bus thread, in real time: none in the simulation, whose model has no turnaround.
  bus.share.broadcast_turnaround = 0;
  BusRuntime::Options o;
  o.clock = &clock_;
  o.stepped = true;
  o.kept_timed = &kept_timed_;  // the parameter server's: a new node resumes what runs
  o.link = &link_;              // its timing (the safe time); the transport counts on top of it
  node_ = std::make_unique<BusRuntime>(std::move(bus), transport_, std::move(o));
  // I22 (docs/share.md): a shared request run in another device's late-reply guard ends
  // before that guard does.
  node_->scheduler().setGuardTimeObserver([this](uint8_t slave, double before, double after) {
    if (checked("I22") && after <= 0)
      fail("I22",
           "a shared request run within slave " + std::to_string(slave) + "'s late-reply guard (" +
               std::to_string(before) +
               " s left) ended after it: that slave's request went later than it would have");
  });
  for (const auto& u : node_->units()) {
    const std::string name = u->name();
    DeviceUnit::Observers seen;
    seen.report = [this](const FailsafeReport& r, const std::string&) {
      if (!dying_) onReport(r);
    };
    seen.poll_starting = [this, name] { onPollStarting(name); };
    seen.polled = [this, name](size_t, const Result& r) { onPolled(name, r); };
    seen.written = [this, name](const std::vector<uint8_t>& c, const std::vector<bool>& st) {
      onWritten(name, c, st);
    };
    u->observe(std::move(seen));
  }
  std::string share_error;
  if (!node_->share()->open(&share_error)) fail("harness", "share: " + share_error);
  const TP started = clock_.now();
  for (int d = 0; d < kGen; ++d)
    if (config_.devices[d].failsafe.on_start_safe)
      for (int ch = 0; ch < kChannels; ++ch)
        if (hasSafe(d, ch)) {
          model_[d].ch[ch].triggered = true;
          model_[d].ch[ch].trigger_at = started;
        }
  // The node's own start (BusRuntime::start), its wait run on the manual clock; I9 is checked
  // where the node readies its topics, before the heartbeats count and the polls start.
  node_->start(awaitOnClock(), [this, started] {
    // I9 (F10): before any command is taken, the safe states are on every device that
    // answered throughout.
    for (int d = 0; d < kGen; ++d) {
      if (!config_.devices[d].failsafe.on_start_safe || model_[d].reachable_since > started ||
          port_lost_ || staleReadShows(d))  // F90: its read before the write took another's frame
        continue;
      for (int ch = 0; ch < kChannels; ++ch)
        if (hasSafe(d, ch) && checked("I9") && simCoil(d, ch) != safeLevel(d, ch))
          fail("I9", std::string(kNames[d]) + " out" + std::to_string(ch) + " is " +
                         (simCoil(d, ch) ? "on" : "off") + " after on_start: safe");
    }
  });
  last_feed_ = dev_last_feed_ = clock_.now();
  lost_ = dev_lost_ = false;
  next_feed_ = clock_.now() + dur(config_.heartbeat / 4);
  if (!config_.devices[kLd].failsafe.heartbeat_topic.empty())
    next_dev_feed_ = clock_.now() + dur(config_.devices[kLd].failsafe.heartbeat_timeout / 4);
  next_tick_ = node_->checkPeriod() > 0 ? clock_.now() + dur(node_->checkPeriod()) : TP::max();
}

void World::stopNode() {
  if (!node_) return;
  const TP began = clock_.now();
  for (int d = 0; d < kGen; ++d)
    for (int ch = 0; ch < kChannels; ++ch)
      if (hasSafe(d, ch)) {
        model_[d].ch[ch].triggered = true;
        model_[d].ch[ch].trigger_at = began;
      }
  next_tick_ = next_feed_ = next_dev_feed_ = TP::max();
  stopping_ = true;
  // The node's own stop (BusRuntime::stop), its wait run on the manual clock.
  const bool confirmed = BusRuntime::allDone(node_->stop(awaitOnClock()));
  // Model change 22 (failsafe.md, the stop's step 5): the list kept for the next node is the
  // one the safe writes left, written after the bus thread ended (the stop flushes it).
  kept_timed_.flush();
  keepRunningTimed();
  // I10 (F5): a device that answered throughout shows its safe states.
  if (confirmed && !port_lost_)
    for (int d = 0; d < kGen; ++d) {
      // F90: a read of the stop's that took another's frame may hide a PWM run there.
      if (model_[d].reachable_since > began || staleReadShows(d)) continue;
      for (int ch = 0; ch < kChannels; ++ch)
        if (hasSafe(d, ch) && checked("I10") && simCoil(d, ch) != safeLevel(d, ch))
          fail("I10", std::string(kNames[d]) + " out" + std::to_string(ch) + " is " +
                          (simCoil(d, ch) ? "on" : "off") + " after the node stopped");
    }
  killNode();
}

void World::killNode() {
  if (!node_) return;
  if (!stopping_) {
    // SIGKILL: the parameter thread's writes not done are lost.
    if (kept_timed_.dropPending() > 0) cover("fault kill before a kept list landed");
    keepRunningTimed();
  }
  dying_ = true;
  stopping_ = false;
  node_.reset();  // queued jobs fail unsent: nothing reaches the line
  dying_ = false;
  pending_.clear();
  next_tick_ = next_feed_ = next_dev_feed_ = TP::max();
}

}  // namespace simulation_world
}  // namespace modbus_rtu_driver
