// The deterministic simulation of the fail-safe (issue #32; docs/simulation.md): one bus with an
// LC relay board, an LD58A08 (PWM), a Yespeed PDU and a generic device, the node's own bus runtime
// (runtime/bus_runtime.h) against the simulator's device models (memory_link.h), on a manual
// clock and one thread. A seed draws the bus's configuration and a sequence of steps (commands from
// every source, triggers, faults, node stop / kill / start); after every step the outcome is
// checked against a model of docs/failsafe.md written apart from the code (failsafe_simulation.cpp,
// each invariant with its line in the docs). The same seed and steps give the same frames, byte for
// byte: their digest says so.
#pragma once

#include <cstdint>
#include <cstdio>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace modbus_rtu_driver {

// One step: a kind and up to four numbers ("set 0 3 1": user sets relays' out3 on).
struct SimStep {
  std::string kind;
  std::vector<int> args;
  std::string text() const;
  // A line as text() writes it; nothing when it is not one.
  static std::optional<SimStep> parse(const std::string& line, std::string* error = nullptr);
};

struct SimFailure {
  size_t step = 0;        // index of the step after which the invariant failed
  std::string invariant;  // "I3"
  std::string message;
  std::vector<std::string> frames;  // the last frames on the line
  std::vector<std::string> steps;   // the last steps
};

struct SimRunResult {
  uint64_t digest = 0;  // every frame, both directions, with its time
  uint64_t frames = 0;
  size_t steps = 0;        // steps run
  double sim_seconds = 0;  // simulated time
  std::optional<SimFailure> failure;
  // Invariants listed as known open defects (run's `known`): how often each failed; the run
  // goes on after them.
  std::vector<std::pair<std::string, uint64_t>> known_failures;
  std::string known_example;  // the first known failure's message
  // How often each path ran (docs/simulation.md, "Coverage"): "step K", "check I", "report
  // TRIGGER TYPE ACTION", "fault F TYPE".
  std::map<std::string, uint64_t> coverage;
};

// The coverage rows a run must hit (`--require-coverage`): every step kind, every invariant
// checked where it could fail, each trigger, device type and action the docs give, each fault
// on each device type.
const std::vector<std::string>& simRequiredCoverage();

class FailsafeSimulation {
 public:
  explicit FailsafeSimulation(uint64_t seed);
  uint64_t seed() const { return seed_; }
  // The bus's configuration this seed draws, in words.
  std::string describe() const;
  // `n` steps drawn from the seed (the same seed gives the same steps).
  std::vector<SimStep> generate(size_t n) const;
  // Runs `steps` on a fresh bus and node from this seed's configuration; stops at the first
  // failed invariant not in `known`.
  SimRunResult run(const std::vector<SimStep>& steps, const std::set<std::string>& known = {},
                   bool keep_history = true) const;
  // The shortest sequence found (steps left out while `invariant` still fails first, the
  // invariants in `known` counted as run() counts them).
  std::vector<SimStep> shrink(std::vector<SimStep> steps, const std::string& invariant,
                              const std::set<std::string>& known = {}) const;
  // Every step, frame and fail-safe report of run() to `out` as they come (nullptr: none).
  void trace(std::FILE* out) { trace_ = out; }

 private:
  uint64_t seed_;
  std::FILE* trace_ = nullptr;
};

// A regression case: the seed (the configuration), the steps, the invariant it failed, and
// whether the defect is fixed (the case must pass now) or a known open one (it must still fail
// with that invariant: a fix makes it pass, and the case is then marked fixed).
struct SimCase {
  uint64_t seed = 0;
  std::string status = "known";  // fixed | known
  std::string invariant;
  // Invariants counted, not failed, while it was shrunk ("known I2,I5"): a replay counts them
  // too, so that the same invariant fails first.
  std::set<std::string> known;
  std::string note;
  std::vector<SimStep> steps;
};
bool writeSimCase(const std::string& path, const SimCase& c, std::string* error);
bool readSimCase(const std::string& path, SimCase* c, std::string* error);

// The invariants checked, by id, with the rules each stands on (docs/invariants.md).
struct SimInvariant {
  const char* id;
  const char* docs;  // "docs/failsafe.md F6, F7": the rules it checks (docs/invariants.md)
  const char* text;
};
const std::vector<SimInvariant>& simInvariants();
// The invariants that fail on known open defects (test/data/simulation/*.case with
// "status known", docs/simulation.md): the timed runs count them and go on. Empty it as they
// are fixed.
const std::set<std::string>& simKnownOpen();

}  // namespace modbus_rtu_driver
