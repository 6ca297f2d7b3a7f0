// World: the steps, the liveness phase and the command steps.
#include "simulation_world.h"

namespace modbus_rtu_driver {
namespace simulation_world {

// ---- steps -------------------------------------------------------------------------------------

bool World::step(const SimStep& s, size_t index) {
  step_index_ = index;
  const std::string& k = s.kind;
  bool k_ran = true;
  auto arg = [&s](size_t i) { return i < s.args.size() ? s.args[i] : 0; };
  if (k == "wait") {
    runFor(arg(0) / 1000.0);
  } else if (k == "hb_stop") {
    alive_ = false;
  } else if (k == "hb_resume") {
    alive_ = true;
  } else if (k == "dhb_stop") {
    dev_alive_ = false;
  } else if (k == "dhb_resume") {
    dev_alive_ = true;
  } else if (k == "silent") {
    const int d = arg(0) % kDevices;
    link_.faults(kAddr[d]).silent = arg(1) != 0;
    if (arg(1) != 0) cover(std::string("fault silent ") + kTypes[d]);
    deviceDisturbed(d, false);
  } else if (k == "lose" || k == "late" || k == "garble") {
    const int d = arg(0) % kDevices;
    MemoryLinkFaults& f = link_.faults(kAddr[d]);
    (k == "lose" ? f.lost : k == "late" ? f.late : f.garbled) = 1 + arg(1) % 3;
    // A late reply arrives just after the timeout (a retry reads it), within the late-reply
    // guard, or after it (a later request's window: incorrect sequence).
    if (k == "late") f.late_by = std::array<double, 3>{0.001, 0.05, 0.3}[arg(2) % 3];
    cover("fault " + k + " " + kTypes[d]);
    deviceDisturbed(d, false);
  } else if (k == "repeat") {
    // The device's next 1-3 replies arrive twice (a repeater sends them again), the copy at
    // once, within an inter-frame time, or 0.15 s later (in the next transaction's window).
    const int d = arg(0) % kDevices;
    MemoryLinkFaults& f = link_.faults(kAddr[d]);
    f.repeated = 1 + arg(1) % 3;
    f.repeat_after = std::array<double, 3>{0.0, 0.02, 0.15}[arg(2) % 3];
    cover(std::string("fault repeat ") + kTypes[d]);
  } else if (k == "refuse") {
    // Exception replies (01, 02, 03, 04, 06) to the device's next requests, whatever they are:
    // polls, commands, safe writes; the device does nothing.
    const int d = arg(0) % kDevices;
    static const uint8_t kCodes[] = {0x01, 0x02, 0x03, 0x04, 0x06};
    MemoryLinkFaults& f = link_.faults(kAddr[d]);
    f.refused = 1 + arg(2) % 3;
    f.refused_code = kCodes[arg(1) % 5];
    cover(std::string("fault refuse ") + kTypes[d]);
    deviceDisturbed(d, false);
  } else if (k == "foreign") {
    // Insertion, masquerade, addressing: a well-formed frame instead of the device's reply.
    const int d = arg(0) % kDevices;
    static const char* const kKinds[] = {"inserted", "masquerade", "addressing"};
    MemoryLinkFaults& f = link_.faults(kAddr[d]);
    f.foreign = 1 + arg(2) % 3;
    f.foreign_kind = static_cast<ForeignFrame>(arg(1) % 3);
    cover(std::string("fault ") + kKinds[arg(1) % 3] + " " + kTypes[d]);
    deviceDisturbed(d, false);
  } else if (k == "port_fail_sent") {
    // The adapter fails during the next transaction, after its request went out.
    link_.failPortAfterNextFrame();
  } else if (k == "power") {
    const int d = arg(0) % kDevices;
    sim(d)->powerCycle(clock_.now());
    cover(std::string("fault power ") + kTypes[d]);
    deviceDisturbed(d, true);
    for (int ch = 0; ch < kChannels; ++ch) {
      Chan& c = model_[d].ch[ch];
      // A run power-down save restarted (F77) shows as the device's only at a poll that
      // reads its registers while it runs; until then its end may show as a change (a report
      // naming the channel is justified); and a run of the node's it stopped likewise.
      const bool saved_run =
          d == kLd && simRegister(kLd, static_cast<uint16_t>(ch * 0x10 + 2)) != 0;
      if (saved_run) {
        c.saved_run_unseen = true;
        c.saved_stop_read_at = TP{};
      } else if (!c.node_run.empty()) {
        c.run_stop_unseen = true;
        c.run_stopped_at = clock_.now();
      }
    }
    // It may restart saved PWM runs (LD58A08 power-down save) and it ended the timed commands
    // the node expects: their ends may show as more changes. The docs do not say what the
    // intent of an interrupted timed command is with on_restart: leave; nothing is checked.
    model_[d].justified_until = std::max(model_[d].justified_until, clock_.now() + dur(8.0));
  } else if (k == "ld_save") {
    sim(kLd)->write(Table::kHoldingRegister, 0x00FA, {static_cast<uint16_t>(arg(0) != 0)},
                    clock_.now());
  } else if (k == "port_lost") {
    link_.setPortLost(true);
    port_lost_ = true;
    for (int d = 0; d < kDevices; ++d) deviceDisturbed(d, false);
  } else if (k == "port_back") {
    link_.setPortLost(false);
    port_lost_ = false;
    // The port is opened again with backoff, up to reconnect_max (5 s).
    for (int d = 0; d < kDevices; ++d) deviceDisturbed(d, false, 5.0);
  } else if (k == "stop") {
    stopNode();
  } else if (k == "kill") {
    killNode();
  } else if (k == "kill_sent") {
    // SIGKILL while a transaction is on the line: its request went out (the device acts on
    // it), and the node dies before the reply. The adapter is not gone: the next node opens it.
    if (node_ && node_->started() && !link_.portLost()) {
      link_.failPortAfterNextFrame();
      killed_frame_out_ = false;
      runUntil(clock_.now() + dur(2.0), [this] { return killed_frame_out_; });
      if (killed_frame_out_) cover("fault kill with a frame on the line");
      link_.clearPortFailure();
      killNode();
      link_.setPortLost(false);
      port_lost_ = false;
    }
  } else if (k == "start") {
    startNode();
  } else if (node_ && node_->started()) {
    doCommandStep(s);
  } else {
    k_ran = false;  // a command while no node runs: nothing to take it
  }
  if (k_ran) cover("step " + k);
  // Every step lets the bus run a little: commands are sent, their answers come.
  if (k != "wait") runFor(0.02);
  if (!failure_) checkHeld();
  return !failure_;
}

bool World::liveness(bool heartbeat_lost) {
  step_index_ = steps_size_;
  // Every fault heals: the devices answer, the port is back (opened again with backoff, up to
  // reconnect_max; each device probed again with backoff, up to backoff_max: 5 s each).
  link_.clearFaults();
  link_.setPortLost(false);
  port_lost_ = false;
  for (int d = 0; d < kDevices; ++d) deviceDisturbed(d, false, 5.0);
  alive_ = dev_alive_ = true;
  if (!node_) startNode();
  // The commands still queued and the owed writes run; what a restart asks is done.
  runFor(15.0);
  if (failure_) return false;
  if (heartbeat_lost) alive_ = dev_alive_ = false;
  // The bound: the longest heartbeat, then the node's stated time after a trigger with what is
  // queued now, and two polls of the slowest device (a held channel disturbed is written again
  // after the good poll that finds it).
  double timeout = config_.heartbeat;
  const DeviceConfig& ld = config_.devices[kLd];
  if (!ld.failsafe.heartbeat_topic.empty())
    timeout = std::max(timeout, ld.failsafe.heartbeat_timeout);
  double slowest = 0;
  for (int d = 0; d < kDevices; ++d) slowest = std::max(slowest, pollPeriod(d));
  const double bound =
      timeout + node_->safeAfterTrigger(node_->queuedJobs()).afterTrigger() + 2 * slowest;
  runFor(bound);
  if (failure_) return false;
  checked("L1");
  for (int d = 0; d < kGen; ++d)
    for (int ch = 0; ch < kChannels; ++ch) {
      const Chan& c = model_[d].ch[ch];
      if (!c.held || !hasSafe(d, ch) || simCoil(d, ch) == safeLevel(d, ch)) continue;
      fail("L1", std::string(kNames[d]) + " out" + std::to_string(ch) + " is held safe (" +
                     safeStateName(safeOf(d, ch)) +
                     ") since t=" + std::to_string(secs(c.held_since - start_)) + " but shows " +
                     (simCoil(d, ch) ? "on" : "off") + " " + std::to_string(bound) +
                     " s after every fault healed and the bus drained (heartbeat " +
                     (heartbeat_lost ? "lost for good" : "alive") + ")");
      return false;
    }
  return !failure_;
}

void World::doCommandStep(const SimStep& s) {
  // Each command step kind's own function (kStepKinds lists every kind with its weight).
  static const std::map<std::string, void (World::*)(const CommandArgs&)> kCommandSteps{
      {"set", &World::stepSet},
      {"set2", &World::stepSet},
      {"command", &World::stepCommand},
      {"pulse", &World::stepPulse},
      {"pwm", &World::stepPwm},
      {"pwm_stop", &World::stepPwmStop},
      {"share05", &World::stepCoilWrite},
      {"raw05", &World::stepCoilWrite},
      {"share15", &World::stepCoilWrite},
      {"raw15", &World::stepCoilWrite},
      {"share15_broadcast", &World::stepShare15Broadcast},
      {"share05_broadcast", &World::stepShare05Broadcast},
      {"raw_broadcast", &World::stepRawBroadcast},
      {"share16_flash", &World::stepFlashRegisters},
      {"raw16_flash", &World::stepFlashRegisters},
      {"share16_pwm", &World::stepShare16Pwm},
      {"share06_stop", &World::stepShare06Stop},
      {"share01", &World::stepShareRead},
      {"signal", &World::stepSignal},
  };
  const auto it = kCommandSteps.find(s.kind);
  if (it == kCommandSteps.end()) return;
  const auto arg = [&s](size_t i) { return i < s.args.size() ? s.args[i] : 0; };
  const int outd = arg(0) % 3;  // an output device: LC, LD58A08, PDU
  const CommandArgs a{s, outd, kNames[outd], static_cast<uint8_t>(arg(1) % kChannels)};
  (this->*it->second)(a);
}

void World::stepSet(const CommandArgs& a) {
  const std::string& k = a.step.kind;
  const auto arg = [&a](size_t i) { return a.arg(i); };
  const int outd = a.outd;
  const std::string& dn = a.dn;
  const uint8_t ch = a.ch;
  std::vector<uint8_t> chs{ch};
  std::vector<bool> sts{arg(2) != 0};
  if (k == "set2") {
    chs.push_back(static_cast<uint8_t>((ch + 2) % kChannels));
    sts.push_back(arg(3) != 0);
  }
  pending_.push_back(set(op("set").id, dn, chs, sts, [this, outd, chs](const Result& r) {
    if (outcomeUnknown(r.error))
      for (uint8_t c : chs) lostAnswer(outd, c, 0);
  }));
}

void World::stepCommand(const CommandArgs& a) {
  const auto arg = [&a](size_t i) { return a.arg(i); };
  const int outd = a.outd;
  const std::string& dn = a.dn;
  const uint8_t ch = a.ch;
  const bool st = arg(2) != 0;
  // F9: a channel turned on through C/command arms its dead man; any command re-arms.
  Chan& c = model_[outd].ch[ch];
  const double timeout = config_.devices[outd].failsafe.commandTimeoutOf(ch);
  if (st && timeout > 0)
    c.deadline = clock_.now() + dur(timeout);
  else
    c.deadline.reset();
  pending_.push_back(command(op("command").id, dn, ch, st, [this, outd, ch](const Result& r) {
    // The merged write's channels come through onWritten; a lost answer leaves the channel
    // unknown until the next poll (F45: a service's or topic's command alike).
    if (outcomeUnknown(r.error)) lostAnswer(outd, ch, 0);
  }));
}

void World::stepPulse(const CommandArgs& a) {
  const auto arg = [&a](size_t i) { return a.arg(i); };
  const uint8_t ch = a.ch;
  const bool st = arg(2) != 0;
  const double seconds = (1 + arg(3) % 40) / 10.0;
  pending_.push_back(
      pulse(op("pulse").id, kNames[kLc], ch, st, seconds, [this, ch, st, seconds](const Result& r) {
        if (r.ok()) {
          // Unless it has ended since the board took it (its job's read
          // back may wait out the late-reply guard).
          const TP took = model_[kLc].flash_heard[ch];
          if (took == TP{} || took + dur(seconds) > clock_.now())
            checkCoils(kLc, {ch}, {st}, "a pulse");
          commandedTimed(kLc, ch, st, !st, seconds);
          // F32: its end counts from the board's answer,
          // not from the read back after it (model change 16).
          Chan& c = model_[kLc].ch[ch];
          const TP answered = model_[kLc].flash_answered[ch];
          if (answered != TP{} && answered <= clock_.now())
            c.ends = c.ends_earliest = answered + dur(seconds);
        } else if (outcomeUnknown(r.error)) {
          lostAnswer(kLc, ch, seconds);
        }
      }));
}

void World::stepPwm(const CommandArgs& a) {
  const auto arg = [&a](size_t i) { return a.arg(i); };
  const uint8_t ch = a.ch;
  PwmSettings p;
  p.channel = ch;
  const int mode = arg(2) % 2;  // 0: timed (burst / fast run), 1: continuous
  double seconds = -1;
  if (ch < 6) {
    p.period = (2 + arg(3) % 8) / 10.0;
    p.on_time = 0.1;
    p.pulses = mode == 0 ? static_cast<uint16_t>(1 + arg(3) % 5) : 0;
    if (mode == 0) seconds = p.pulses * p.period;
  } else {
    p.frequency = 100;
    p.duty_cycle = 50;
    p.duration = mode == 0 ? (1 + arg(3) % 30) / 10.0 : 0;
    if (mode == 0) seconds = p.duration;
  }
  pending_.push_back(setPwm(op("pwm").id, kNames[kLd], p, [this, ch, seconds, p](const Result& r) {
    if (r.ok()) {
      // Unless it has ended since the device took it (the job's reads may wait out late
      // replies and the late-reply guard).
      const TP took = model_[kLd].pwm_heard[ch];
      const bool may_run = seconds < 0 || took == TP{} || took + dur(seconds) > clock_.now();
      if (simRegister(kLd, static_cast<uint16_t>(ch * 0x10 + 2)) == 0 && seconds > 1.5 && may_run)
        fail("I1", "pwm out" + std::to_string(ch) +
                       ": set_pwm was confirmed but the channel "
                       "does not run");
      // (A burst shorter than a lost answer's timeouts and read back may have ended.)
      // F28: a burst or timed run is the device's until its end, then off. A
      // continuous one is the node's to start again (docs "What restore writes"): its
      // registers as the manual encodes them.
      const std::vector<uint16_t> regs =
          ch < 6 ? std::vector<uint16_t>{static_cast<uint16_t>(std::lround(p.period * 10)),
                                         static_cast<uint16_t>(std::lround(p.on_time * 10)), 0xFFFF}
                 : std::vector<uint16_t>{static_cast<uint16_t>(p.frequency),
                                         static_cast<uint16_t>(p.duty_cycle), 0xFFFF};
      commandedTimed(kLd, ch, std::nullopt, false, seconds,
                     seconds < 0 ? regs : std::vector<uint16_t>{});
      Chan& c = model_[kLd].ch[ch];
      if (c.timed && model_[kLd].pwm_write_answered[ch] != TP{})
        c.ends_earliest = std::min(c.ends, model_[kLd].pwm_write_answered[ch] + dur(seconds));
    } else if (outcomeUnknown(r.error)) {
      lostPwmRun(ch, seconds);
    }
  }));
}

void World::stepPwmStop(const CommandArgs& a) {
  const uint8_t ch = a.ch;
  pending_.push_back(stopPwm(op("pwm_stop").id, kNames[kLd], ch, [this, ch](const Result& r) {
    if (r.ok()) {
      // F90 (model change 31): a read back that took another request's late reply (beyond
      // the guard, or with the guard at 0) may confirm a stop the device did not do.
      if (simRegister(kLd, static_cast<uint16_t>(ch * 0x10 + 2)) != 0 && !staleReadShows(kLd))
        fail("I1", "pwm out" + std::to_string(ch) + ": stop_pwm was confirmed but it runs");
      // A PWM command (F18) ends the hold; the level shows at the next poll.
      commanded(kLd, ch, false);
      unconfirmed(kLd, ch, 0, true);
      // Precedence counts from when the device confirmed the stop (F18, "a command
      // confirmed after the trigger"), not from when the step saw its result (model change 15).
      Chan& stopped = model_[kLd].ch[ch];
      const TP answered = model_[kLd].stop_answered[ch];
      if (answered != TP{} && answered <= clock_.now()) stopped.adopt_at = answered;
      model_[kLd].ch[ch].known = false;
    } else if (outcomeUnknown(r.error)) {
      lostAnswer(kLd, ch, 0);
    }
  }));
}

void World::stepCoilWrite(const CommandArgs& a) {
  const std::string& k = a.step.kind;
  const auto arg = [&a](size_t i) { return a.arg(i); };
  const int outd = a.outd;
  const uint8_t ch = a.ch;
  const bool via_share = k[0] == 's';
  Request req;
  std::vector<uint8_t> chs;
  std::vector<bool> sts;
  if (k == "share05" || k == "raw05") {
    req = Request::writeSingleCoil(kAddr[outd], ch, arg(2) != 0);
    chs = {ch};
    sts = {arg(2) != 0};
    if (!via_share) req = Request::writeMultipleCoils(kAddr[outd], ch, {arg(2) != 0});
  } else {
    const int n = 1 + arg(3) % std::min(4, kChannels - ch);
    std::vector<bool> bits;
    for (int i = 0; i < n; ++i) {
      bits.push_back(((arg(2) >> i) & 1) != 0);
      chs.push_back(static_cast<uint8_t>(ch + i));
    }
    sts = bits;
    req = Request::writeMultipleCoils(kAddr[outd], ch, bits);
  }
  DeviceUnit::Done done = [this, outd, chs, sts, k](const Result& r) {
    if (r.ok()) {
      for (size_t i = 0; i < chs.size(); ++i) {
        // A client's coil write is the device's to confirm (the node passes its answer on):
        // I1 on the LC board and the PDU. An LD58A08 channel running a PWM acknowledges a
        // coil write and goes on running (its manual), and the model does not follow every
        // run (a killed node's, one a power cycle restarted): no I1 there.
        if (outd != kLd) checkCoils(outd, {chs[i]}, {sts[i]}, k);
        // F49: the coils a write names are taken as commanded at once; F30: on an
        // LD58A08 channel the node last read as running a PWM the run goes on: the device's.
        const Chan& was = model_[outd].ch[chs[i]];
        // (F30, F31: as the node last read it, a continuous run the device confirmed counting
        // as read running; or a timed run of the node's before its end.)
        // (F31: and a PWM write whose answer was lost, until its end plus the slack.)
        const DevModel& ld = model_[kLd];
        const TP now = clock_.now();
        const bool runs =
            outd == kLd && (ld.pwm_read_running[chs[i]] || (was.timed && now < was.ends_earliest) ||
                            ld.lost_run_for_good[chs[i]] || now < ld.lost_run_until[chs[i]]);
        // The node's run ends its duration after the device answered the write; the model's
        // op learns it later (after the read back): in between, either may be right. So
        // may a lost run's window near its end (the node's clock and the model's differ by
        // the step's callback).
        const bool may_run =
            outd == kLd && !runs &&
            ((was.timed && now < was.ends) ||
             (ld.lost_run_until[chs[i]] != TP{} && now < ld.lost_run_until[chs[i]] + dur(0.05)));
        commanded(outd, chs[i], sts[i]);
        if (runs) {
          // F30, F31: the run goes on, and counts as read running until a read.
          model_[kLd].ch[chs[i]].continuous = true;
          model_[kLd].pwm_read_running[chs[i]] = true;
        }
        if (may_run) model_[kLd].ch[chs[i]].maybe_devices = true;
      }
    } else if (outcomeUnknown(r.error)) {
      for (uint8_t c : chs) lostAnswer(outd, c, 0);
    }
  };
  pending_.push_back(via_share ? share(op(k).id, req, done) : raw(op(k).id, req, done));
}

void World::stepShare15Broadcast(const CommandArgs& a) {
  const std::string& k = a.step.kind;
  const auto arg = [&a](size_t i) { return a.arg(i); };
  const uint8_t ch = a.ch;
  // docs "What happens when", the share's row: a broadcast (unit 0) confirms nothing. Every
  // device that listens applies it (a silent one does not); on each, the coils it names are
  // as after a write whose answer was lost: unknown until the next poll, taken as found,
  // no hold ended, no owed write cancelled (I2, I3 and I4 keep watching them).
  const int n = 1 + arg(3) % std::min(4, kChannels - ch);
  std::vector<bool> bits(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) bits[static_cast<size_t>(i)] = ((arg(2) >> i) & 1) != 0;
  const Request req = Request::writeMultipleCoils(kBroadcastAddress, ch, bits);
  pending_.push_back(share(op(k).id, req, [this, ch, n](const Result& r) {
    if (!r.ok() && !outcomeUnknown(r.error)) return;  // refused or unsent: nothing changed
    for (int d = 0; d < kGen; ++d)
      for (int i = 0; i < n; ++i) lostAnswer(d, ch + i, 0);
  }));
}

void World::stepShare05Broadcast(const CommandArgs& a) {
  const std::string& k = a.step.kind;
  const auto arg = [&a](size_t i) { return a.arg(i); };
  const uint8_t ch = a.ch;
  // The same with FC05: one coil on every listening device.
  const Request req = Request::writeSingleCoil(kBroadcastAddress, ch, arg(2) % 2 != 0);
  pending_.push_back(share(op(k).id, req, [this, ch](const Result& r) {
    if (!r.ok() && !outcomeUnknown(r.error)) return;  // refused or unsent: nothing changed
    for (int d = 0; d < kGen; ++d) lostAnswer(d, ch, 0);
  }));
}

void World::stepRawBroadcast(const CommandArgs& a) {
  const std::string& k = a.step.kind;
  const auto arg = [&a](size_t i) { return a.arg(i); };
  const uint8_t ch = a.ch;
  // docs/ros_api.md (write_coils, write_registers): a raw write to slave 0 is refused at
  // once, unsent (a broadcast is never confirmed).
  const uint64_t frames = link_.frames();
  const Request req = arg(2) % 2 == 0
                          ? Request::writeMultipleCoils(kBroadcastAddress, ch, {arg(3) % 2 != 0})
                          : Request::writeMultipleRegisters(kBroadcastAddress, ch, {1});
  std::future<Result> f = raw(op(k).id, req, nullptr);
  const bool refused = f.wait_for(std::chrono::seconds(0)) == std::future_status::ready &&
                       f.get().error == ErrorKind::kInvalidArgument;
  if (checked("I12") && (!refused || link_.frames() != frames))
    fail("I12", "a raw " + req.describe() + " was " +
                    (refused ? "refused but something went on the line" : "not refused at once"));
}

void World::stepFlashRegisters(const CommandArgs& a) {
  const std::string& k = a.step.kind;
  const auto arg = [&a](size_t i) { return a.arg(i); };
  const uint8_t ch = a.ch;
  // An LC flash through its registers (F21): mode 4 close, 2 open; delay in 0.1 s.
  const bool close = arg(2) % 2 == 0;
  const auto tenths = static_cast<uint16_t>(1 + arg(3) % 40);
  const Request req = Request::writeMultipleRegisters(kAddr[kLc], static_cast<uint16_t>(3 + 5 * ch),
                                                      {close ? uint16_t{4} : uint16_t{2}, tenths});
  DeviceUnit::Done done = [this, ch, close, tenths, k](const Result& r) {
    if (r.ok()) {
      checkCoils(kLc, {ch}, {close}, k);
      commandedTimed(kLc, ch, close, !close, tenths / 10.0);
    } else if (outcomeUnknown(r.error)) {
      lostAnswer(kLc, ch, tenths / 10.0);
    }
  };
  pending_.push_back(k[0] == 's' ? share(op(k).id, req, done) : raw(op(k).id, req, done));
}

void World::stepShare16Pwm(const CommandArgs& a) {
  const std::string& k = a.step.kind;
  const auto arg = [&a](size_t i) { return a.arg(i); };
  const uint8_t ch = a.ch;
  // An LD58A08 PWM run through its registers (period, on-time, enable = pulses).
  const auto c6 = static_cast<uint8_t>(ch % 6);
  const auto period = static_cast<uint16_t>(2 + arg(3) % 8);
  const auto pulses = static_cast<uint16_t>(arg(2) % 2 == 0 ? 1 + arg(3) % 5 : 0xFFFF);
  const Request req = Request::writeMultipleRegisters(kAddr[kLd], static_cast<uint16_t>(c6 * 0x10),
                                                      {period, 1, pulses});
  pending_.push_back(share(op(k).id, req, [this, c6, period, pulses](const Result& r) {
    if (r.ok()) {
      commandedTimed(
          kLd, c6, std::nullopt, false, pulses == 0xFFFF ? -1.0 : pulses * period / 10.0,
          pulses == 0xFFFF ? std::vector<uint16_t>{period, 1, pulses} : std::vector<uint16_t>{});
    } else if (outcomeUnknown(r.error)) {
      lostPwmRun(c6, pulses == 0xFFFF ? -1.0 : pulses * period / 10.0);
    }
  }));
}

void World::stepShare06Stop(const CommandArgs& a) {
  const std::string& k = a.step.kind;
  const uint8_t ch = a.ch;
  // The enable register to 0: a write the type does not decode as a run (F26).
  const Request req =
      Request::writeSingleRegister(kAddr[kLd], static_cast<uint16_t>(ch * 0x10 + 2), 0);
  pending_.push_back(share(op(k).id, req, [this, ch](const Result& r) {
    if (r.ok()) {
      unconfirmed(kLd, ch, 0, true);
      // The run is stopped (F30: no longer one the node knows not yet ended).
      model_[kLd].ch[ch].continuous = model_[kLd].ch[ch].timed = false;
    }
    if (outcomeUnknown(r.error)) lostAnswer(kLd, ch, 0);
  }));
}

// A client's read of an output device's coils (FC01): the traffic that uses other devices'
// late-reply guards (docs/share.md), also cut short there and retried after the guarded request.
// Its answer is the device's, as the link decoded it (the link's tests check that).
void World::stepShareRead(const CommandArgs& a) {
  const uint64_t id = op(a.step.kind).id;
  share_read_attempts_[id] = 0;  // onAttempt counts them: I22
  pending_.push_back(share(id, Request::readCoils(kAddr[a.outd], 0, kChannels), nullptr));
}

void World::stepSignal(const CommandArgs& a) {
  const std::string& k = a.step.kind;
  const auto arg = [&a](size_t i) { return a.arg(i); };
  const size_t signal = static_cast<size_t>(arg(0) % 2);
  const double value = signal == 0 ? arg(1) % 2 : (arg(1) % 6) * 10.0;
  pending_.push_back(
      writeSignal(op(k).id, kNames[kGen], signal, value, [this, signal](const Result& r) {
        if (r.ok()) model_[kGen].gen_set_at[signal] = clock_.now();
      }));
}

}  // namespace simulation_world
}  // namespace modbus_rtu_driver
