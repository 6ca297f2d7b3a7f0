#include "modbus_rtu_driver/simulation/failsafe_simulation.h"

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
#include "modbus_rtu_driver/simulation/memory_kept_timed.h"
#include "modbus_rtu_driver/simulation/memory_link.h"

namespace modbus_rtu_driver {

// ---------------------------------------------------------------------------------------------
// The invariants (docs/invariants.md). Each stands on rules of docs/failsafe.md (F1, F2, ...:
// the spec); the model below is written from those rules, not from the code. Where the docs
// are silent the model checks nothing (docs/simulation.md lists those questions).
const std::vector<SimInvariant>& simInvariants() {
  static const std::vector<SimInvariant> list = {
      {"I1", "docs/failsafe.md F21, F28, F29, F49; README (writes are confirmed)",
       "a command reported as done (service, topic, pulse, PWM, share, raw write) is on the "
       "device when its answer comes"},
      {"I2", "docs/failsafe.md F6-F9, F16, F17, F58, F59, F87",
       "a channel held safe (heartbeat lost, command timeout) shows its safe state on a device "
       "that answers, within the timeout's tenth plus the bus transactions before it"},
      {"I3", "docs/failsafe.md F12, F16, F19, F20, F36",
       "a fail-safe write (restore, safe states, owed writes) never writes a held channel other "
       "than safe"},
      {"I4", "docs/failsafe.md F12, F21, F22, F25, F36, F44",
       "a fail-safe write changes a channel from its intent (the newest confirmed command, or "
       "the found state) only for a reason: a trigger since, or a restart of the device since "
       "(on_restart: safe writes safe, restore the timed command's final level)"},
      {"I5", "docs/failsafe.md F12, F36-F39, F41, F78",
       "a restore writes, channel by channel, the safe state of a held or owed channel, else a "
       "timed command's final level, else the intent's level (found states included); never a "
       "continuous PWM channel as a level; and every channel whose intent is known; it starts "
       "again, as written, the node's continuous PWM run the read before shows stopped, and a "
       "power cycle that stopped one is seen within 8 polls of the device answering"},
      {"I6", "docs/failsafe.md F11, F25, F32-F35, F45, F77, F80, F81, F84",
       "a restart 'outputs changed with no command in between' is reported only after "
       "something did change them without the node's confirmed command (a power cycle, a "
       "write whose reply was lost, a flash of a killed node)"},
      {"I7", "docs/troubleshooting.md (writes that start something are never sent twice)",
       "a frame that starts something (a flash, a PWM run) reaches the device at most once per "
       "transaction"},
      {"I8", "docs/failsafe.md F70-F72",
       "generic device: a safe value the device refuses does not stop the others, and is not "
       "retried while the device answers; a signal set since the trigger is not written, one "
       "not set since is"},
      {"I9", "docs/failsafe.md F10",
       "on_start: safe: the safe states are on every answering device before commands are taken"},
      {"I10", "docs/failsafe.md F5, F60-F64, F66",
       "node stop: the safe states are on every answering device when the stop's writes end"},
      {"I11", "docs/failsafe.md F1, F5, F7",
       "a write of safe states (a trigger's, on_restart: safe, an owed one) writes only channels "
       "whose safe state is not hold: a channel nobody asked to write is not written"},
      {"I12", "docs/ros_api.md (write_coils, write_registers)",
       "a raw write to slave 0 (broadcast) is refused at once, and nothing goes on the line"},
      {"I21", "docs/failsafe.md F90; troubleshooting.md (late replies)",
       "a device's reply that comes within late_reply_guard after its request timed out is "
       "never taken as the reply to a different request"},
      {"I22", "docs/share.md (shared requests in a late-reply guard); docs/failsafe.md F90",
       "a shared request run while another device's late-reply guard holds the line ends "
       "before that guard does: the guarded request starts no later than without it"},
      {"L1", "docs/failsafe.md F8, F16, F17, F41, F58 (safe until commanded again, owed writes)",
       "liveness: once every fault heals (the devices answer, the port is back, a node runs), "
       "every channel held safe (the heartbeat lost, for good in half the seeds, or a command "
       "timeout) shows its safe state within the node's stated bound"},
  };
  return list;
}

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
    {"raw_broadcast", 1}, {"repeat", 2},      {"kill_sent", 1}};

const std::vector<std::string>& simRequiredCoverage() {
  static const std::vector<std::string> rows = [] {
    std::vector<std::string> r;
    for (const StepKind& k : kStepKinds) r.push_back(std::string("step ") + k.name);
    for (const SimInvariant& i : simInvariants()) r.push_back(std::string("check ") + i.id);
    for (const char* f : {"silent", "lose", "late", "garble", "power", "refuse", "inserted",
                          "masquerade", "addressing", "repeat"})
      for (const char* t : {"lc_relay8", "ld58a08", "yespeed_pdu", "generic"})
        r.push_back(std::string("fault ") + f + " " + t);
    // A kill between a change of the kept timed commands and its parameter write (model
    // change 28), and a new node resuming a command from a list that was behind.
    r.emplace_back("fault kill before a kept list landed");
    r.emplace_back("fault resumed from a list behind the killed node");
    r.emplace_back("fault kill with a frame on the line");
    // docs/share.md: a shared request to another device within a device's late-reply guard.
    r.emplace_back("path shared request in another device's guard");
    // The fail-safe's events, by trigger, device type and action (docs/failsafe.md, "What
    // happens when"): written and confirmed, or owed ("(unconfirmed)": the device was silent).
    for (const char* t : {"lc_relay8", "ld58a08", "yespeed_pdu", "generic"}) {
      const std::string type = t;
      for (const char* trigger : {"heartbeat", "start", "shutdown"}) {
        r.push_back(std::string("report ") + trigger + " " + type + " safe");
        r.push_back(std::string("report ") + trigger + " " + type + " safe (unconfirmed)");
      }
      r.push_back("report restart " + type + " safe");  // on_restart: safe; generic: owed values
      if (type == "generic") continue;
      r.push_back("report command_timeout " + type + " safe");
      r.push_back("report command_timeout " + type + " safe (unconfirmed)");
      r.push_back("report restart " + type + " restore");
      r.push_back("report restart " + type + " leave");
    }
    return r;
  }();
  return rows;
}

const std::set<std::string>& simKnownOpen() {
  // docs/simulation.md, "Known open defects": an invariant a case shows broken on today's code
  // goes here, with its case "status known". None since stop 57.
  static const std::set<std::string> known = {};
  return known;
}

namespace {

using TP = Clock::time_point;
Clock::duration dur(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}
double secs(Clock::duration d) {
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

Config drawConfig(uint64_t seed) {
  Rng r{seed ^ 0xC0FFEEull};
  Config c;
  c.link.port = "memory";
  c.link.baud = r.pick({9600, 19200});
  c.link.response_timeout = r.pick({0.05, 0.1, 0.2});
  c.link.retries = r.pick({0, 1, 2});
  c.link.late_reply_guard = 0;
  c.heartbeat = r.pick({0.3, 0.5, 1.0});
  for (int d = 0; d < kDevices; ++d) {
    DeviceConfig dc;
    dc.name = kNames[d];
    dc.type = kTypes[d];
    dc.address = kAddr[d];
    dc.poll_rate = r.pick({2.0, 5.0, 10.0});
    FailsafeConfig& fs = dc.failsafe;
    fs.on_start_safe = r.chance(50);
    if (d != kGen) {
      fs.on_restart = r.pick({OnRestart::kRestore, OnRestart::kSafe, OnRestart::kLeave});
      fs.safe_state.resize(kChannels);
      fs.command_timeout.assign(kChannels, 0.0);
      for (int ch = 0; ch < kChannels; ++ch) {
        const int k = r.below(10);
        fs.safe_state[ch] = k < 4 ? SafeState::kHold : k < 8 ? SafeState::kOff : SafeState::kOn;
        if (fs.safe_state[ch] != SafeState::kHold && r.chance(30))
          fs.command_timeout[ch] = r.pick({0.3, 1.0, 2.0});
      }
    } else {
      SignalConfig run;
      run.name = "run";
      run.table = Table::kCoil;
      run.address = 0;
      run.type = SignalType::kBool;
      run.writable = true;
      run.safe_value = r.chance(70) ? 0.0 : 1.0;
      SignalConfig speed;
      speed.name = "speed";
      speed.table = Table::kHoldingRegister;
      speed.address = 0x10;
      speed.type = SignalType::kInt16;
      speed.scale = 0.1;
      speed.unit = "Hz";
      speed.writable = true;
      speed.min = 0.0;
      speed.max = 50.0;
      speed.safe_value = r.pick({0.0, 10.0, 25.0});
      SignalConfig mode;
      mode.name = "mode";
      mode.table = Table::kHoldingRegister;
      mode.address = 0x20;
      mode.type = SignalType::kUint16;
      mode.writable = true;
      mode.safe_value = 3.0;
      dc.generic.signals = {run, speed, mode};
      c.generic_refuses = r.chance(50);
    }
    c.devices.push_back(dc);
  }
  c.ld_save = r.chance(30);
  // The LD58A08's own heartbeat (F7: that device only) in half the seeds; drawn last,
  // so the draws above stay what they were.
  if (r.chance(50)) {
    c.devices[kLd].failsafe.heartbeat_topic = "pwm_alive";
    c.devices[kLd].failsafe.heartbeat_timeout = r.pick({0.3, 1.0});
  }
  // Drawn after every other draw, so that those stay what they were.
  c.kept_latency = r.pick({0.0, 0.0, 0.05, 0.3});
  // The link's late-reply guard (docs/ros_api.md; default 0.1 s), or none.
  c.link.late_reply_guard = r.pick({0.1, 0.1, 0.0});
  return c;
}

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
  bool hasSafe(int d, int ch) const { return safeOf(d, ch) != SafeState::kHold; }
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
  void doCommandStep(const SimStep& s);
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
  uint64_t ran_in_guards_ = 0;  // the node's scheduler's count, as last seen
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
  node_->beginStart();
  // BusNode::start waits shutdown_timeout + 5 s for them.
  runUntil(started + dur(config_.shutdown_timeout + 5.0),
           [this] { return node_->startWritesDone(); });
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
  node_->finishStart();
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
  node_->beginStop();
  stopping_ = true;
  runUntil(began + dur(config_.shutdown_timeout), [this] { return node_->stopWritesDone(); });
  // Model change 22 (failsafe.md, the stop's step 5): the list kept for the next node is the
  // one the safe writes left, written after the bus thread ended (the stop flushes it).
  kept_timed_.flush();
  keepRunningTimed();
  // I10 (F5): a device that answered throughout shows its safe states.
  if (node_->stopWritesDone() && !port_lost_)
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
      cover("report " + r.trigger + " " + kTypes[d] + " " + r.action +
            (r.confirmed ? "" : " (unconfirmed)"));
  if (trace_) std::fprintf(trace_, "report %s: %s\n", r.device.c_str(), r.text().c_str());
  const int d = devOf(r.device);
  if (d == kGen) return onGenericReport(r);
  DevModel& m = model_[d];
  const TP now = clock_.now();
  std::vector<int> chs;
  chs.reserve(r.channels.size());
  for (const std::string& name : r.channels) chs.push_back(name[3] - '0');  // out0..out7
  if (r.trigger == "restart") {
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
  if (r.action == "safe") {
    // I11 (F1): "Nothing changes unless it is configured: the default safe state is hold".
    for (size_t i = 0; i < chs.size(); ++i)
      if (checked("I11") && !hasSafe(d, chs[i]))
        fail("I11", std::string(kNames[d]) + " out" + std::to_string(chs[i]) +
                        " (safe state hold) is written by a safe write (" + r.trigger + ")");
  }
  // A restore's entries that started a continuous PWM run again (FailsafeReport::runs), and
  // whether it wrote plain levels too.
  auto isRun = [&r](size_t i) { return i < r.runs.size() && r.runs[i]; };
  bool plain = false;
  for (size_t i = 0; i < chs.size(); ++i) plain = plain || !isRun(i);
  if (r.action == "restore") {
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
  } else if (r.trigger == "heartbeat" || r.trigger == "command_timeout" || r.trigger == "start" ||
             r.trigger == "shutdown") {
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
  if (r.trigger == "restart" && checked("I8") && !m.gen_prev_silent)
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
    if (listed[i] && r.trigger == "restart" && m.gen_set_at[i] > m.gen_report_at)
      fail("I8", "drive: the owed safe write (restart) wrote " + signals[i].name +
                     ", set since its trigger fired");
    if (!listed[i] && r.trigger != "restart" && m.gen_set_at[i] <= m.gen_written_at[i])
      fail("I8", "drive: the safe write (" + r.trigger + ") left " + signals[i].name +
                     " out, not set since it was last written safe");
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
                       "write (" + r.trigger + "), not its safe value " +
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
  const std::string& k = s.kind;
  auto arg = [&s](size_t i) { return i < s.args.size() ? s.args[i] : 0; };
  const int outd = arg(0) % 3;  // an output device: LC, LD58A08, PDU
  const std::string dn = kNames[outd];
  const auto ch = static_cast<uint8_t>(arg(1) % kChannels);
  if (k == "set" || k == "set2") {
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
  } else if (k == "command") {
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
  } else if (k == "pulse") {
    const bool st = arg(2) != 0;
    const double seconds = (1 + arg(3) % 40) / 10.0;
    pending_.push_back(pulse(op("pulse").id, kNames[kLc], ch, st, seconds,
                             [this, ch, st, seconds](const Result& r) {
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
  } else if (k == "pwm") {
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
    pending_.push_back(
        setPwm(op("pwm").id, kNames[kLd], p, [this, ch, seconds, p](const Result& r) {
          if (r.ok()) {
            // Unless it has ended since the device took it (the job's reads may wait out late
            // replies and the late-reply guard).
            const TP took = model_[kLd].pwm_heard[ch];
            const bool may_run = seconds < 0 || took == TP{} || took + dur(seconds) > clock_.now();
            if (simRegister(kLd, static_cast<uint16_t>(ch * 0x10 + 2)) == 0 && seconds > 1.5 &&
                may_run)
              fail("I1", "pwm out" + std::to_string(ch) +
                             ": set_pwm was confirmed but the channel "
                             "does not run");
            // (A burst shorter than a lost answer's timeouts and read back may have ended.)
            // F28: a burst or timed run is the device's until its end, then off. A
            // continuous one is the node's to start again (docs "What restore writes"): its
            // registers as the manual encodes them.
            const std::vector<uint16_t> regs =
                ch < 6 ? std::vector<uint16_t>{static_cast<uint16_t>(std::lround(p.period * 10)),
                                               static_cast<uint16_t>(std::lround(p.on_time * 10)),
                                               0xFFFF}
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
  } else if (k == "pwm_stop") {
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
  } else if (k == "share05" || k == "raw05" || k == "share15" || k == "raw15") {
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
              outd == kLd &&
              (ld.pwm_read_running[chs[i]] || (was.timed && now < was.ends_earliest) ||
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
  } else if (k == "share15_broadcast") {
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
  } else if (k == "share05_broadcast") {
    // The same with FC05: one coil on every listening device.
    const Request req = Request::writeSingleCoil(kBroadcastAddress, ch, arg(2) % 2 != 0);
    pending_.push_back(share(op(k).id, req, [this, ch](const Result& r) {
      if (!r.ok() && !outcomeUnknown(r.error)) return;  // refused or unsent: nothing changed
      for (int d = 0; d < kGen; ++d) lostAnswer(d, ch, 0);
    }));
  } else if (k == "raw_broadcast") {
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
  } else if (k == "share16_flash" || k == "raw16_flash") {
    // An LC flash through its registers (F21): mode 4 close, 2 open; delay in 0.1 s.
    const bool close = arg(2) % 2 == 0;
    const auto tenths = static_cast<uint16_t>(1 + arg(3) % 40);
    const Request req = Request::writeMultipleRegisters(
        kAddr[kLc], static_cast<uint16_t>(3 + 5 * ch), {close ? uint16_t{4} : uint16_t{2}, tenths});
    DeviceUnit::Done done = [this, ch, close, tenths, k](const Result& r) {
      if (r.ok()) {
        checkCoils(kLc, {ch}, {close}, k);
        commandedTimed(kLc, ch, close, !close, tenths / 10.0);
      } else if (outcomeUnknown(r.error)) {
        lostAnswer(kLc, ch, tenths / 10.0);
      }
    };
    pending_.push_back(k[0] == 's' ? share(op(k).id, req, done) : raw(op(k).id, req, done));
  } else if (k == "share16_pwm") {
    // An LD58A08 PWM run through its registers (period, on-time, enable = pulses).
    const auto c6 = static_cast<uint8_t>(ch % 6);
    const auto period = static_cast<uint16_t>(2 + arg(3) % 8);
    const auto pulses = static_cast<uint16_t>(arg(2) % 2 == 0 ? 1 + arg(3) % 5 : 0xFFFF);
    const Request req = Request::writeMultipleRegisters(
        kAddr[kLd], static_cast<uint16_t>(c6 * 0x10), {period, 1, pulses});
    pending_.push_back(share(op(k).id, req, [this, c6, period, pulses](const Result& r) {
      if (r.ok()) {
        commandedTimed(
            kLd, c6, std::nullopt, false, pulses == 0xFFFF ? -1.0 : pulses * period / 10.0,
            pulses == 0xFFFF ? std::vector<uint16_t>{period, 1, pulses} : std::vector<uint16_t>{});
      } else if (outcomeUnknown(r.error)) {
        lostPwmRun(c6, pulses == 0xFFFF ? -1.0 : pulses * period / 10.0);
      }
    }));
  } else if (k == "share06_stop") {
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
  } else if (k == "signal") {
    const size_t signal = static_cast<size_t>(arg(0) % 2);
    const double value = signal == 0 ? arg(1) % 2 : (arg(1) % 6) * 10.0;
    pending_.push_back(
        writeSignal(op(k).id, kNames[kGen], signal, value, [this, signal](const Result& r) {
          if (r.ok()) model_[kGen].gen_set_at[signal] = clock_.now();
        }));
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------

std::string SimStep::text() const {
  std::string t = kind;
  for (int a : args) t += " " + std::to_string(a);
  return t;
}

std::optional<SimStep> SimStep::parse(const std::string& line, std::string* error) {
  std::istringstream in(line);
  SimStep s;
  if (!(in >> s.kind)) {
    if (error) *error = "empty line";
    return std::nullopt;
  }
  static const std::set<std::string> kinds = [] {
    std::set<std::string> names;
    for (const StepKind& k : kStepKinds) names.insert(k.name);
    return names;
  }();
  if (!kinds.count(s.kind)) {
    if (error) *error = "unknown step '" + s.kind + "'";
    return std::nullopt;
  }
  int a = 0;
  while (in >> a) s.args.push_back(a);
  if (!in.eof()) {
    if (error) *error = "'" + line + "': arguments must be integers";
    return std::nullopt;
  }
  return s;
}

FailsafeSimulation::FailsafeSimulation(uint64_t seed) : seed_(seed) {}

std::string FailsafeSimulation::describe() const {
  const Config c = drawConfig(seed_);
  std::ostringstream o;
  o << "link " << c.link.baud << " baud, response_timeout " << c.link.response_timeout
    << " s, retries " << c.link.retries << "; heartbeat " << c.heartbeat << " s"
    << (c.ld_save ? "; LD58A08 power-down save on" : "")
    << (c.kept_latency > 0 ? "; kept lists land " + numberText(c.kept_latency) + " s late" : "")
    << "\n";
  for (const DeviceConfig& d : c.devices) {
    o << "  " << d.name << " (" << d.type << " @" << d.address << ", " << d.poll_rate << " Hz): ";
    if (d.type == "generic") {
      o << "safe values";
      for (const SignalConfig& s : d.generic.signals) {
        o << " " << s.name << "=";
        if (s.safe_value)
          o << *s.safe_value;
        else
          o << "none";
      }
      o << (c.generic_refuses ? " (mode refused)" : "") << ", on_start "
        << (d.failsafe.on_start_safe ? "safe" : "keep") << "\n";
      continue;
    }
    o << "safe";
    for (int ch = 0; ch < kChannels; ++ch) {
      o << " " << safeStateName(d.failsafe.safeStateOf(ch));
      if (d.failsafe.commandTimeoutOf(ch) > 0) o << "/" << d.failsafe.commandTimeoutOf(ch) << "s";
    }
    o << ", on_restart " << onRestartName(d.failsafe.on_restart) << ", on_start "
      << (d.failsafe.on_start_safe ? "safe" : "keep");
    if (!d.failsafe.heartbeat_topic.empty())
      o << ", own heartbeat " << d.failsafe.heartbeat_timeout << " s";
    o << "\n";
  }
  return o.str();
}

std::vector<SimStep> FailsafeSimulation::generate(size_t n) const {
  Rng r{seed_};
  std::vector<SimStep> steps;
  steps.push_back({"start", {}});
  // Weights: mostly commands and time, then triggers, faults and the node's life.
  using Kind = StepKind;
  const auto& kinds = kStepKinds;
  int total = 0;
  for (const Kind& k : kinds) total += k.weight;
  while (steps.size() < n) {
    int x = r.below(total);
    const Kind* k = kinds;
    while (x >= k->weight) x -= (k++)->weight;
    SimStep s;
    s.kind = k->name;
    if (s.kind == "wait") {
      s.args = {r.pick({10, 50, 100, 300, 700, 1500})};
    } else if (s.kind == "silent") {
      s.args = {r.below(kDevices), r.chance(50) ? 1 : 0};
    } else if (s.kind == "hb_stop" || s.kind == "hb_resume" || s.kind == "dhb_stop" ||
               s.kind == "dhb_resume" || s.kind == "port_lost" || s.kind == "port_back" ||
               s.kind == "stop" || s.kind == "kill" || s.kind == "kill_sent" || s.kind == "start" ||
               s.kind == "port_fail_sent") {
    } else {
      s.args = {r.below(kDevices), r.below(kChannels), r.below(16), r.below(64)};
    }
    steps.push_back(s);
  }
  return steps;
}

SimRunResult FailsafeSimulation::run(const std::vector<SimStep>& steps,
                                     const std::set<std::string>& known, bool keep_history) const {
  SimRunResult out;
  std::deque<std::string> recent;
  auto world = std::make_unique<World>(seed_, known, keep_history, trace_);
  world->setHistory(&recent);
  for (size_t i = 0; i < steps.size(); ++i) {
    if (keep_history) {
      recent.push_back(std::to_string(i) + ": " + steps[i].text());
      if (recent.size() > 30) recent.pop_front();
    }
    ++out.steps;
    if (trace_)
      std::fprintf(trace_, "step %zu t=%.3f: %s\n", i, world->simSeconds(),
                   steps[i].text().c_str());
    if (!world->step(steps[i], i)) break;
  }
  // The liveness phase, after every step ran without a failure: the heartbeat lost for good in
  // half the seeds.
  if (!world->failure() && out.steps == steps.size()) {
    if (trace_) std::fprintf(trace_, "liveness t=%.3f\n", world->simSeconds());
    world->setStepsSize(steps.size());
    world->liveness(seed_ % 2 == 0);
  }
  out.digest = world->digest();
  out.frames = world->frames();
  out.sim_seconds = world->simSeconds();
  out.failure = world->failure();
  for (const auto& [id, n] : world->knownFailures()) out.known_failures.emplace_back(id, n);
  out.known_example = world->knownExample();
  out.coverage = world->coverage();
  return out;
}

std::vector<SimStep> FailsafeSimulation::shrink(std::vector<SimStep> steps,
                                                const std::string& invariant,
                                                const std::set<std::string>& known) const {
  auto fails = [&](const std::vector<SimStep>& s) {
    const SimRunResult r = run(s, known, false);
    return r.failure && r.failure->invariant == invariant;
  };
  {
    const SimRunResult r = run(steps, known, false);
    if (!r.failure || r.failure->invariant != invariant) return steps;
    // (A failure of the liveness phase is at step steps.size(): every step stays.)
    steps.resize(std::min(steps.size(), r.failure->step + 1));
  }
  // Drop chunks, halving their size, while it still fails (delta debugging, roughly).
  for (size_t chunk = std::max<size_t>(1, steps.size() / 2); chunk >= 1; chunk /= 2) {
    bool removed = true;
    while (removed) {
      removed = false;
      for (size_t at = 0; at < steps.size();) {
        std::vector<SimStep> shorter = steps;
        const size_t n = std::min(chunk, shorter.size() - at);
        shorter.erase(shorter.begin() + static_cast<long>(at),
                      shorter.begin() + static_cast<long>(at + n));
        if (!shorter.empty() && fails(shorter)) {
          steps = shorter;
          removed = true;
        } else {
          at += chunk;
        }
      }
    }
    if (chunk == 1) break;
  }
  return steps;
}

bool writeSimCase(const std::string& path, const SimCase& c, std::string* error) {
  std::ofstream out(path);
  if (!out) {
    if (error) *error = "cannot write " + path;
    return false;
  }
  out << "# A failsafe_simulation regression case (docs/simulation.md): replayed by\n"
      << "# test_failsafe_simulation; `failsafe_simulation --replay FILE` prints its run.\n";
  if (!c.note.empty()) {
    std::istringstream note(c.note);
    std::string line;
    while (std::getline(note, line)) out << "# " << line << "\n";
  }
  out << "seed " << c.seed << "\n";
  out << "status " << c.status << "\n";
  out << "invariant " << c.invariant << "\n";
  if (!c.known.empty()) {
    out << "known ";
    for (auto it = c.known.begin(); it != c.known.end(); ++it)
      out << (it == c.known.begin() ? "" : ",") << *it;
    out << "\n";
  }
  for (const SimStep& s : c.steps) out << s.text() << "\n";
  return static_cast<bool>(out);
}

bool readSimCase(const std::string& path, SimCase* c, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    if (error) *error = "cannot read " + path;
    return false;
  }
  std::string line;
  int n = 0;
  bool seeded = false;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    if (line.rfind("seed ", 0) == 0) {
      c->seed = std::stoull(line.substr(5));
      seeded = true;
      continue;
    }
    if (line.rfind("invariant ", 0) == 0) {
      c->invariant = line.substr(10);
      continue;
    }
    if (line.rfind("known ", 0) == 0) {
      std::istringstream ids(line.substr(6));
      std::string id;
      while (std::getline(ids, id, ','))
        if (!id.empty()) c->known.insert(id);
      continue;
    }
    if (line.rfind("status ", 0) == 0) {
      c->status = line.substr(7);
      if (c->status != "fixed" && c->status != "known") {
        if (error)
          *error = path + ":" + std::to_string(n) + ": status: '" + c->status +
                   "' is neither fixed nor known";
        return false;
      }
      continue;
    }
    std::string why;
    auto s = SimStep::parse(line, &why);
    if (!s) {
      if (error) *error = path + ":" + std::to_string(n) + ": " + why;
      return false;
    }
    c->steps.push_back(*s);
  }
  if (!seeded) {
    if (error) *error = path + ": no 'seed N' line";
    return false;
  }
  return true;
}

}  // namespace modbus_rtu_driver
