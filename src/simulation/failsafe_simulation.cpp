#include "modbus_rtu_driver/simulation/failsafe_simulation.h"

#include "simulation_world.h"

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
       "every attempt of a shared request run while another device's late-reply guard holds "
       "the line ends before that guard does: the guarded request starts no later than without "
       "it; a read cut short there gets its remaining retries later, never more attempts in all "
       "than retries allows"},
      {"L1", "docs/failsafe.md F8, F16, F17, F41, F58 (safe until commanded again, owed writes)",
       "liveness: once every fault heals (the devices answer, the port is back, a node runs), "
       "every channel held safe (the heartbeat lost, for good in half the seeds, or a command "
       "timeout) shows its safe state within the node's stated bound"},
  };
  return list;
}

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
    // ... a read cut short there: its remaining retries after the guarded request.
    r.emplace_back("path a shared read's retries after the guarded request");
    // failsafe.md F90: a new read with a failed read's frame takes its late reply, no guard.
    r.emplace_back("path a new read took its frame's late reply within the guard");
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

using namespace simulation_world;

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
        << (d.failsafe.on_start_safe ? "safe" : "leave") << "\n";
      continue;
    }
    o << "safe";
    for (int ch = 0; ch < kChannels; ++ch) {
      o << " " << safeStateName(d.failsafe.safeStateOf(ch));
      if (d.failsafe.commandTimeoutOf(ch) > 0) o << "/" << d.failsafe.commandTimeoutOf(ch) << "s";
    }
    o << ", on_restart " << onRestartName(d.failsafe.on_restart) << ", on_start "
      << (d.failsafe.on_start_safe ? "safe" : "leave");
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