// The fail-safe simulation's world (internal to src/simulation): the configuration a seed
// draws, the model of docs/failsafe.md per channel and device, and World, which runs the
// node's bus runtime on the memory line and checks the invariants. World's parts are in
// files by concern: simulation_world_life.cpp (time, the node's life), _line.cpp (the
// model's inputs, every attempt on the line), _reports.cpp (polls, fail-safe reports, held
// channels), _steps.cpp (the steps); simulation_config.cpp draws the configuration.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <deque>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>

#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/devices/generic_device.h"
#include "modbus_rtu_driver/devices/ld58a08.h"
#include "modbus_rtu_driver/runtime/bus_runtime.h"
#include "modbus_rtu_driver/sim/sim_generic.h"
#include "modbus_rtu_driver/sim/sim_lc_relay8.h"
#include "modbus_rtu_driver/sim/sim_ld58a08.h"
#include "modbus_rtu_driver/sim/sim_yespeed_pdu.h"
#include "modbus_rtu_driver/simulation/failsafe_simulation.h"
#include "modbus_rtu_driver/simulation/memory_kept_timed.h"
#include "modbus_rtu_driver/simulation/memory_link.h"

namespace modbus_rtu_driver {

// Every step kind, once (SimStep::parse, the draw, the coverage rows), with its weight in the
// draw: mostly commands and time, then triggers, faults and the node's life.
struct StepKind {
  const char* name;
  int weight;
};
constexpr StepKind kStepKinds[] = {
    {"wait", 26},         {"set", 8},         {"set2", 3},           {"command", 6},
    {"pulse", 4},         {"pwm", 4},         {"pwm_stop", 2},       {"share05", 3},
    {"share15", 2},       {"raw05", 1},       {"raw15", 1},          {"share16_flash", 2},
    {"raw16_flash", 1},   {"share16_pwm", 2}, {"share06_stop", 1},   {"signal", 2},
    {"hb_stop", 3},       {"hb_resume", 4},   {"dhb_stop", 2},       {"dhb_resume", 3},
    {"silent", 3},        {"lose", 2},        {"late", 1},           {"garble", 2},
    {"power", 2},         {"ld_save", 1},     {"port_lost", 1},      {"port_back", 3},
    {"stop", 1},          {"kill", 1},        {"start", 3},          {"share15_broadcast", 1},
    {"refuse", 2},        {"foreign", 2},     {"port_fail_sent", 1}, {"share05_broadcast", 1},
    {"raw_broadcast", 1}, {"repeat", 2},      {"kill_sent", 1},      {"share01", 3}};

namespace simulation_world {

using TP = Clock::time_point;
inline Clock::duration dur(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}
inline double secs(Clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

struct Rng {
  uint64_t s;
  uint64_t next() {  // splitmix64: the same numbers on every platform
    uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  int below(int n) { return static_cast<int>(next() % static_cast<uint64_t>(n)); }
  bool chance(int percent) { return below(100) < percent; }
  template <typename T>
  T pick(std::initializer_list<T> items) {
    return *(items.begin() + below(static_cast<int>(items.size())));
  }
};

enum Dev { kLc = 0, kLd = 1, kPdu = 2, kGen = 3, kDevices = 4 };
const char* const kNames[kDevices] = {"relays", "pwm", "pdu", "drive"};
const char* const kTypes[kDevices] = {"lc_relay8", "ld58a08", "yespeed_pdu", "generic"};
const uint8_t kAddr[kDevices] = {1, 2, 3, 4};
constexpr int kChannels = 8;

// ---------------------------------------------------------------------------------------------
// The configuration a seed draws.
struct Config {
  LinkConfig link;
  double heartbeat = 0.5;
  double shutdown_timeout = 3.0;
  std::vector<DeviceConfig> devices;
  bool generic_refuses = false;  // one safe value lands in a hole of the device's map
  bool ld_save = false;          // the LD58A08's power-down save at the start
  // s the parameter server's kept lists lag the node (its parameter thread; 0: none).
  double kept_latency = 0;
};

// The configuration seed `seed` draws (simulation_config.cpp).
Config drawConfig(uint64_t seed);

// ---------------------------------------------------------------------------------------------
// The model of docs/failsafe.md, per output channel.
struct Chan {
  bool known = false;    // the intent is known (F21, F22, F26); unknown after an unconfirmed write
  bool command = false;  // the intent is a confirmed command (not found, restore or safe)
  bool level = false;    // the steady level; a timed command's final level (F28, F32)
  bool timed = false;
  std::optional<bool> during;  // a timed command's level until its end (none: any)
  TP ends{};
  double duration = 0;
  // F33: a poll after the end (within its slack: one showing the final level) ended the
  // timed command there; a write whose answer is lost after that waits for no end (model
  // change 26: the model followed which poll that was only for restores before).
  bool settled = false;
  bool continuous = false;  // a PWM run with no end: the device's (F28, F37)
  // docs "What restore writes": a continuous run this node started (set_pwm, a client's FC16 of
  // the channel's three registers), its registers; a restore starts it again when the read just
  // before shows it stopped. Empty otherwise.
  std::vector<uint16_t> node_run;
  // ... and a power cycle may have stopped it since: the poll that reads its registers (one
  // channel per poll) reports a restart for it (docs "Restart detection needs polls").
  bool run_stop_unseen = false;
  TP run_stopped_at{};
  // A run power-down save restarted (F77): the device's once a poll reads it running;
  // until then its start and its end may each show as a change (a restart report naming the
  // channel is justified), the end up to the report after a poll read it stopped.
  bool saved_run_unseen = false;
  TP saved_stop_read_at{};
  bool maybe_devices = false;  // read running near the node's run's end: either may be right
  // A set_pwm's end counted from when the device answered its write (the node's end); `ends`
  // counts from the model's callback, a read back later.
  TP ends_earliest{};
  bool from_old_node = false;  // a timed command the previous node kept, resumed by this one
  TP at{};
  // The node's timed command may still run at `t`: before its end plus the slack (F32).
  bool nodeRuns(TP t) const { return timed && t <= ends + dur(0.5 + 0.02 * duration); }
  // F37, F33: a run read at `t` may be the device's: no timed command of the node's runs then,
  // or a poll after the end that showed the final level may have ended it (the model does not
  // follow which poll that was: past the end the node counts from the device's answer).
  bool runMayBeDevices(TP t) const { return !nodeRuns(t) || t > ends_earliest; }
  // When what the node keeps for this channel for the next node last changed (a command, a
  // timed command, a write whose outcome is unknown): the list lags it by kept_latency.
  TP kept_changed_at{};
  bool kept_lagging = false;  // carried from a list that had not caught up (model change 28)
  // A kept timed command that ended about when this node started (model change 36): the node
  // may have resumed it (its final level the intent) or found the channel at its first good poll;
  // the model cannot tell which, so the channel is not checked until it is commanded again.
  bool kept_uncertain = false;
  bool held = false;  // F16-F20
  TP held_since{};
  size_t queued_at_hold = 0;  // jobs queued on the bus when the hold began
  bool owed = false;          // F40-F43
  bool triggered = false;     // a trigger covered it (start, shutdown, heartbeat, command timeout)
  TP trigger_at{};
  std::optional<TP> deadline;  // the dead man (F9)
  bool adopt = false;          // take the level of a poll started after `adopt_after_poll`
  bool adopt_is_command = false;
  uint64_t adopt_after_poll = 0;
  TP adopt_not_before{};
  TP adopt_at{};                 // when the write was confirmed
  bool shown_otherwise = false;  // held, and the last poll showed it not in its safe state
  // Held, and a write nobody confirmed (its answer lost, a broadcast) may have changed it since
  // then: safe again once a poll found it otherwise (the share's row of "What happens when").
  TP disturbed_at{};
  TP disturbed_poll_at{};  // the good poll that found it after that write (none yet: {})
  bool adopt_prev_known = false, adopt_prev_level = false;  // what it should show before
};

struct DevModel {
  std::vector<Chan> ch;
  bool justified = false;  // I6: something changed outputs the node did not confirm
  // Polls since the node took a repeated or late frame as a read's reply: that poll may report
  // a change, and the next one the change back (what it took as found was not the device's);
  // on an LD58A08 the poll that reads that channel's PWM registers again, up to 8 polls on.
  int polls_since_stale = 1000;
  TP stale_read_at{};
  // LD58A08: a channel whose PWM registers a read took from another request's frame, not read
  // again by a poll since (F90: what follows may be wrong until the poll that reads them again).
  std::vector<bool> stale_pwm_unread = std::vector<bool>(8, false);
  TP justified_at{};           // ... at this time
  TP justified_until{};        // ... and goes on changing them until then (a timed command)
  std::optional<TP> cause_at;  // I4: the newest thing that may make the node see a restart
  bool cause_pending = false;  // ... not yet followed by a restart report
  TP last_poll_at{};           // the end of its newest good poll
  TP prev_poll_at{};           // ... and of the one before it
  TP reachable_since{};        // no fault, no power cycle, port open, node running since
  uint64_t polls_started = 0;
  uint64_t poll_running = 0;  // the sequence number of the poll running now
  bool in_poll = false;       // between a poll's start and its end
  // ... and a write to the device was noted since that start: its reads may predate the write,
  // so it is no "good poll" for found states (F23).
  bool written_in_poll = false;
  // A fail-safe write went out: its read back (F37, F79, a read of the device's state) is next.
  bool readback_pending = false;
  std::vector<bool> fs_written = std::vector<bool>(8, false);  // ... the channels it wrote
  bool unanswered = false;  // an attempt went unanswered since its last good poll
  bool found = false;
  // LD58A08: whether a channel's PWM ran when the node last read its registers (F37: a
  // restore leaves a run the device reports; the node knows only what it read)
  std::vector<bool> pwm_read_running = std::vector<bool>(8, false);
  // F31: a PWM write whose answer was lost counts as a run until its end plus the slack
  // (counted from when the loss was learned, as the node counts it), or for good for a
  // continuous one, until a confirmed stop or a read that shows the channel not running.
  std::vector<TP> lost_run_until = std::vector<TP>(8, TP{});
  std::vector<bool> lost_run_for_good = std::vector<bool>(8, false);
  // ... as it was when the fail-safe's newest write went out (F37: read just before it)
  std::vector<bool> pwm_read_at_write = std::vector<bool>(8, false);
  // ... and the poll that read each channel's registers (F46: a lost answer's channel is
  // taken at the first poll after its time that also reads them)
  std::vector<uint64_t> pwm_read_in_poll = std::vector<uint64_t>(8, 0);
  // A channel's PWM registers as a fail-safe operation's own read (not a poll's, not a read back)
  // last showed them since the last poll: what the read just before a restore found (F37).
  std::vector<bool> run_read_in_op = std::vector<bool>(8, false);
  // ... and when the device last answered a PWM write (FC16 of a channel's three registers):
  // the node counts a set_pwm's end from there (F32), the model's op from its later callback
  // Jobs queued on the bus when it became reachable (checkHeld notes it once per spell).
  size_t queued_at_reachable = 0;
  bool queued_noted = false;
  std::vector<TP> pwm_write_answered = std::vector<TP>(8, TP{});
  std::vector<TP> stop_answered = std::vector<TP>(8, TP{});   // a 0 to the enable register
  std::vector<TP> flash_answered = std::vector<TP>(8, TP{});  // an LC flash's FC16
  std::vector<TP> pwm_heard = std::vector<TP>(8, TP{});       // an LD58A08 run's FC16 reached it
  std::vector<TP> flash_heard = std::vector<TP>(8, TP{});     // an LC flash's FC16 reached it
  // ... and whether it ran as last read when the fail-safe's write starting it again went out
  // (docs "What restore writes": started again only when the read just before shows it stopped)
  std::vector<bool> run_read_at_start = std::vector<bool>(8, false);
  std::vector<bool> pwm_confirm_pending = std::vector<bool>(8, false);
  // generic (I8)
  bool gen_unanswered = false;  // an attempt to it went unanswered since its last report
  bool gen_prev_silent = true;  // ... before its previous report
  // Addresses whose write the device refused with an exception since its last report (a
  // refused safe value is reported, not on the device: F70, F71).
  std::set<uint16_t> gen_refused;
  TP gen_report_at{};  // its previous report
  // per signal: its newest set the device confirmed, and the newest report that wrote it
  std::vector<TP> gen_set_at = std::vector<TP>(3, TP{});
  std::vector<TP> gen_written_at = std::vector<TP>(3, TP{});
};

struct Operation {
  uint64_t id = 0;
  std::string what;
};

class World {
 public:
  World(uint64_t seed, const std::set<std::string>& known, bool keep_history, std::FILE* trace)
      : config_(drawConfig(seed)),
        known_(known),
        link_(config_.link, clock_),
        transport_(link_),
        trace_(trace) {
    link_.keepHistory(keep_history ? 40 : 0);
    link_.trace(trace);
    kept_timed_.setLatency(config_.kept_latency);
    SimLineSettings line;
    line.baud = config_.link.baud;
    link_.addDevice(std::make_unique<SimLcRelay8>(kAddr[kLc], line));
    link_.addDevice(std::make_unique<SimLd58a08>(kAddr[kLd], line));
    link_.addDevice(std::make_unique<SimYespeedPdu>(kAddr[kPdu], line, clock_.now()));
    SimGenericConfig gc;
    gc.map = config_.devices[kGen].generic;
    if (config_.generic_refuses)
      gc.holes.push_back({Table::kHoldingRegister, 0x20, 0x20});  // "mode" is refused
    else
      gc.holes.push_back({Table::kHoldingRegister, 0x30, 0x30});
    link_.addDevice(std::make_unique<SimGeneric>(kAddr[kGen], line, gc));
    if (config_.ld_save) sim(kLd)->write(Table::kHoldingRegister, 0x00FA, {1}, clock_.now());
    link_.onAttempt([this](const LineEvent& e) { onAttempt(e); });
    for (auto& m : model_) m.ch.resize(kChannels);
    start_ = clock_.now();
  }
  ~World() { killNode(); }

  // Runs one step; false when an invariant failed (failure_ says which).
  bool step(const SimStep& s, size_t index);
  // After the steps (docs/simulation.md, "Liveness"): every fault heals, a node runs, the bus
  // drains; then the heartbeat is lost for good (`heartbeat_lost`) or stays alive, and every
  // held channel must show its safe state within the stated bound (L1).
  bool liveness(bool heartbeat_lost);
  const std::optional<SimFailure>& failure() const { return failure_; }
  uint64_t digest() const { return link_.digest(); }
  uint64_t frames() const { return link_.frames(); }
  double simSeconds() const { return secs(clock_.now() - start_); }
  const std::map<std::string, uint64_t>& knownFailures() const { return known_hits_; }
  const std::map<std::string, uint64_t>& coverage() const { return coverage_; }
  const std::string& knownExample() const { return known_example_; }
  void setStepsSize(size_t n) { steps_size_ = n; }
  void setHistory(const std::deque<std::string>* steps) { steps_ = steps; }

 private:
  SimDevice* sim(int d) { return link_.device(kAddr[d]); }
  bool simCoil(int d, int ch) {
    uint16_t v = 0;
    sim(d)->read(Table::kCoil, static_cast<uint16_t>(ch), clock_.now(), &v);
    return v != 0;
  }
  uint16_t simRegister(int d, uint16_t address) {
    uint16_t v = 0;
    sim(d)->read(Table::kHoldingRegister, address, clock_.now(), &v);
    return v;
  }
  SafeState safeOf(int d, int ch) const { return config_.devices[d].failsafe.safeStateOf(ch); }
  bool safeLevel(int d, int ch) const { return safeOf(d, ch) == SafeState::kOn; }
  bool hasSafe(int d, int ch) const { return safeOf(d, ch) != SafeState::kLeave; }
  OnRestart onRestart(int d) const { return config_.devices[d].failsafe.on_restart; }
  int devOf(uint8_t address) const {
    for (int d = 0; d < kDevices; ++d)
      if (kAddr[d] == address) return d;
    return -1;
  }
  int devOf(const std::string& name) const {
    for (int d = 0; d < kDevices; ++d)
      if (name == kNames[d]) return d;
    return -1;
  }
  double pollPeriod(int d) const { return 1.0 / config_.devices[d].poll_rate; }

  void fail(const std::string& invariant, const std::string& message);
  // Counts a coverage row (docs/simulation.md, "Coverage").
  void cover(const std::string& row) { ++coverage_[row]; }
  // F90: the node took a repeated or late frame as a read of device `d`, and no poll has read
  // the same again since (on an LD58A08, the one that reads that channel's PWM registers: up
  // to 8 polls on).
  bool staleReadShows(int d) const {
    const DevModel& m = model_[d];
    return m.polls_since_stale <= (d == kLd ? 10 : 2) ||
           std::find(m.stale_pwm_unread.begin(), m.stale_pwm_unread.end(), true) !=
               m.stale_pwm_unread.end();
  }
  // An invariant is about to be compared in a state where it could fail: counted; true.
  bool checked(const char* invariant) {
    cover(std::string("check ") + invariant);
    return true;
  }
  void runFor(double seconds);
  void runUntil(TP end, const std::function<bool()>& done = {});
  // The node's wait for its start's and stop's safe writes (BusRuntime::AwaitWrites): the bus
  // runs on the manual clock until they are done or the deadline has come.
  BusRuntime::AwaitWrites awaitOnClock();
  void tick();
  void startNode();
  void stopNode();
  void killNode();
  void resetModelForNewNode();
  void keepRunningTimed();
  void onAttempt(const LineEvent& e);
  void onReport(const FailsafeReport& r);
  void onGenericReport(const FailsafeReport& r);
  void takeFoundAfterRestart(int d, const FailsafeReport& r);
  void onPollStarting(const std::string& device);
  void onPolled(const std::string& device, const Result& r);
  void onWritten(const std::string& device, const std::vector<uint8_t>& chs,
                 const std::vector<bool>& sts);
  // Model updates.
  void commanded(int d, int ch, bool level);
  void commandedTimed(int d, int ch, std::optional<bool> during, bool after, double seconds,
                      const std::vector<uint16_t>& run = {});
  void unconfirmed(int d, int ch, double not_before_s, bool as_command);
  void hold(int d, int ch);
  // F45, F46: a command whose answer was lost (any source) leaves its channel unknown until the
  // next poll, whose level is taken as found: for a timed command of `seconds`, or a write on a
  // channel where a timed command still runs, the first poll after that end plus the slack.
  void lostAnswer(int d, int ch, double seconds);
  void lostPwmRun(int ch, double seconds);  // seconds < 0: a continuous run
  void deviceDisturbed(int d, bool justified, double extra = 0);
  bool expected(const Chan& c, TP t, bool* level) const;
  // Invariants checked after each step.
  void checkHeld();
  void checkCoils(int d, const std::vector<uint8_t>& chs, const std::vector<bool>& sts,
                  const std::string& what);
  // Steps.
  // A command step's arguments as every kind reads them: an output device (LC, LD58A08, PDU),
  // its name, a channel, and the step's numbers (0 past the last).
  struct CommandArgs {
    const SimStep& step;
    int outd = 0;
    std::string dn;
    uint8_t ch = 0;
    int arg(size_t i) const { return i < step.args.size() ? step.args[i] : 0; }
  };
  // Runs a command step by its kind's function below.
  void doCommandStep(const SimStep& s);
  void stepSet(const CommandArgs& a);
  void stepCommand(const CommandArgs& a);
  void stepPulse(const CommandArgs& a);
  void stepPwm(const CommandArgs& a);
  void stepPwmStop(const CommandArgs& a);
  void stepCoilWrite(const CommandArgs& a);
  void stepShare15Broadcast(const CommandArgs& a);
  void stepShare05Broadcast(const CommandArgs& a);
  void stepRawBroadcast(const CommandArgs& a);
  void stepFlashRegisters(const CommandArgs& a);
  void stepShare16Pwm(const CommandArgs& a);
  void stepShare06Stop(const CommandArgs& a);
  void stepShareRead(const CommandArgs& a);
  void stepSignal(const CommandArgs& a);
  // The node's calls as its services, topics, share and raw write services make them, tagged
  // with the step's operation; `done` (the model) runs on the bus thread at the job's end.
  using Done = DeviceUnit::Done;
  DeviceUnit& unitOf(const std::string& device) { return *node_->unit(device); }
  std::future<Result> set(uint64_t op, const std::string& device,
                          const std::vector<uint8_t>& channels, const std::vector<bool>& states,
                          Done done) {
    return unitOf(device).set(channels, states, {op, std::move(done)});
  }
  std::future<Result> command(uint64_t op, const std::string& device, uint8_t channel, bool state,
                              Done done) {
    return unitOf(device).command(channel, state, {op, std::move(done)});
  }
  std::future<Result> pulse(uint64_t op, const std::string& device, uint8_t channel, bool state,
                            double seconds, Done done) {
    return unitOf(device).pulse(channel, state, seconds, {op, std::move(done)});
  }
  std::future<Result> setPwm(uint64_t op, const std::string& device, const PwmSettings& p,
                             Done done) {
    return unitOf(device).setPwm(p, {op, std::move(done)});
  }
  std::future<Result> stopPwm(uint64_t op, const std::string& device, uint8_t channel, Done done) {
    return unitOf(device).stopPwm(channel, {op, std::move(done)});
  }
  std::future<Result> writeSignal(uint64_t op, const std::string& device, size_t signal,
                                  double value, Done done) {
    return unitOf(device).writeSignal(signal, value, {op, std::move(done)});
  }
  std::future<Result> raw(uint64_t op, const Request& request, Done done) {
    return node_->rawWrite(request, {op, std::move(done)});
  }
  // A share client's request (its answer's bytes go nowhere: no client checks them here).
  std::future<Result> share(uint64_t op, const Request& request, Done done) {
    node_->share()->forward(
        request, [](const Bytes&) {}, std::move(done), op);
    return {};
  }
  Operation op(const std::string& what) { return {++op_seq_, what}; }

  Config config_;
  std::set<std::string> known_;
  ManualClock clock_;
  MemoryLink link_;
  CountingTransport transport_;
  // running_timed/<device> on the parameter server: kept across nodes, as roscore outlives a
  // killed or respawned node.
  MemoryKeptTimed kept_timed_{clock_};
  // The node's bus runtime, the node's own (runtime/bus_runtime.h), stepped on the manual clock.
  std::unique_ptr<BusRuntime> node_;  // after kept_timed_: it writes there
  std::map<std::string, uint64_t> coverage_;
  uint64_t ran_in_guards_ = 0;                   // the node's scheduler's count, as last seen
  uint64_t cut_in_guards_ = 0;                   // likewise
  std::map<uint64_t, int> share_read_attempts_;  // each share01 read's attempts, by its op
  bool dying_ = false;
  bool stopping_ = false;
  bool killed_frame_out_ = false;  // kill_sent: the frame it waits for went out
  TP start_{};
  DevModel model_[kDevices];
  // docs/failsafe.md "A node started during a flash": the timed commands still running when the
  // node died, or when it began to stop (its shutdown keeps nothing more), which the next node
  // resumes.
  std::vector<std::optional<Chan>> carried_[kDevices];
  // The controller and its heartbeat (F6-F8).
  bool alive_ = true;
  TP last_feed_{};
  bool lost_ = false;
  size_t steps_size_ = 0;  // the run's steps: the liveness phase's step index
  // The LD58A08's own heartbeat and its controller.
  bool dev_alive_ = true;
  TP dev_last_feed_{};
  bool dev_lost_ = false;
  TP next_tick_ = TP::max(), next_feed_ = TP::max(), next_dev_feed_ = TP::max();
  uint64_t op_seq_ = 0;
  std::map<uint64_t, int> starts_by_transaction_;  // I7
  std::optional<SimFailure> failure_;
  size_t step_index_ = 0;
  std::map<std::string, uint64_t> known_hits_;
  std::string known_example_;
  const std::deque<std::string>* steps_ = nullptr;
  std::vector<std::future<Result>> pending_;
  bool port_lost_ = false;
  std::FILE* trace_ = nullptr;
};

}  // namespace simulation_world

}  // namespace modbus_rtu_driver
