// failsafe_simulation: the deterministic simulation of the fail-safe (docs/simulation.md).
//   failsafe_simulation [--seed S] [--seeds N | --seconds T] [--steps N] [--known I5,I6]
//                       [--cases DIR] [--junit FILE] [--require-coverage] [--replay FILE]
// Runs seeds S, S+1, ... (each a bus configuration and `steps` steps) for N seeds or T seconds;
// every seed runs twice at first to show that its digest repeats. A failure prints the seed,
// the step, the invariant, the last frames and steps, is shrunk, and is written to DIR as a
// regression case. At the end, the coverage table: how often each path ran; with
// --require-coverage a required row without a hit is a failure. Exit 1 on a failure
// (invariants in --known are counted, not failed).
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "modbus_rtu_driver/simulation/failsafe_simulation.h"

using namespace modbus_rtu_driver;

namespace {

void usage() {
  std::fprintf(stderr,
               "usage: failsafe_simulation [--seed S] [--seeds N | --seconds T] [--steps N]\n"
               "         [--known I5,I6] [--cases DIR] [--junit FILE] [--require-coverage]\n"
               "         [--replay FILE [--trace]] "
               "[--quiet]\n");
}

std::string xml(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<')
      o += "&lt;";
    else if (c == '>')
      o += "&gt;";
    else if (c == '&')
      o += "&amp;";
    else if (c == '"')
      o += "&quot;";
    else
      o += c;
  }
  return o;
}

void printFailure(uint64_t seed, const SimFailure& f) {
  std::printf("FAILURE seed %llu step %zu invariant %s\n  %s\n",
              static_cast<unsigned long long>(seed), f.step, f.invariant.c_str(),
              f.message.c_str());
  for (const SimInvariant& i : simInvariants())
    if (f.invariant == i.id) std::printf("  (%s: %s)\n", i.docs, i.text);
  std::printf("  last steps:\n");
  for (const std::string& s : f.steps) std::printf("    %s\n", s.c_str());
  std::printf("  last frames:\n");
  for (const std::string& s : f.frames) std::printf("    %s\n", s.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  uint64_t seed = 1;
  long seeds = -1;
  double seconds = -1;
  size_t steps = 2000;
  std::set<std::string> known = simKnownOpen();  // --known none: check them all
  bool known_given = false;
  std::string cases, junit, replay;
  bool quiet = false;
  bool require_coverage = false;  // a required coverage row without a hit is a failure
  bool trace = false;             // --replay: every step, frame and report on stderr
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* name) -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s: needs a value\n", name);
        std::exit(2);
      }
      return argv[++i];
    };
    try {
      if (a == "--seed")
        seed = std::stoull(value("--seed"));
      else if (a == "--seeds")
        seeds = std::stol(value("--seeds"));
      else if (a == "--seconds")
        seconds = std::stod(value("--seconds"));
      else if (a == "--steps")
        steps = std::stoul(value("--steps"));
      else if (a == "--cases")
        cases = value("--cases");
      else if (a == "--junit")
        junit = value("--junit");
      else if (a == "--replay")
        replay = value("--replay");
      else if (a == "--quiet")
        quiet = true;
      else if (a == "--require-coverage")
        require_coverage = true;
      else if (a == "--trace")
        trace = true;
      else if (a == "--known") {
        known.clear();
        known_given = true;
        std::istringstream in(value("--known"));
        std::string id;
        while (std::getline(in, id, ','))
          if (!id.empty() && id != "none") known.insert(id);
      } else {
        usage();
        return 2;
      }
    } catch (const std::exception&) {
      std::fprintf(stderr, "%s: not a number\n", a.c_str());
      return 2;
    }
  }
  if (!cases.empty()) mkdir(cases.c_str(), 0755);  // an existing one is fine
  if (steps < 1 || steps > 10000000) {
    std::fprintf(stderr, "--steps: %zu is outside 1-10000000\n", steps);
    return 2;
  }

  if (!replay.empty()) {
    SimCase c;
    std::string error;
    if (!readSimCase(replay, &c, &error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
      return 2;
    }
    FailsafeSimulation sim(c.seed);
    if (trace) sim.trace(stderr);
    std::printf("replay %s: seed %llu, %zu steps, %s %s\n%s", replay.c_str(),
                static_cast<unsigned long long>(c.seed), c.steps.size(), c.status.c_str(),
                c.invariant.empty() ? "none" : c.invariant.c_str(), sim.describe().c_str());
    // As the gtest replays it: the case's own known list (unless --known says otherwise).
    const SimRunResult r = sim.run(c.steps, known_given ? known : c.known);
    std::printf("digest %016llx, %llu frames, %.1f s simulated\n",
                static_cast<unsigned long long>(r.digest),
                static_cast<unsigned long long>(r.frames), r.sim_seconds);
    if (r.failure)
      printFailure(c.seed, *r.failure);
    else
      std::printf("no failure\n");
    // A known case must still fail with its invariant, a fixed one must pass.
    const bool as_expected =
        c.status == "fixed" ? !r.failure : r.failure && r.failure->invariant == c.invariant;
    std::printf("%s case: %s\n", c.status.c_str(), as_expected ? "as expected" : "NOT as expected");
    return as_expected ? 0 : 1;
  }

  if (seeds < 0 && seconds < 0) seeds = 1;
  const auto began = std::chrono::steady_clock::now();
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  };
  uint64_t total_steps = 0, total_frames = 0, runs = 0, failures = 0;
  double sim_seconds = 0;
  std::map<std::string, uint64_t> known_hits;
  std::map<std::string, uint64_t> coverage;
  std::vector<std::string> failure_texts;
  std::string known_example;
  double last_print = 0;
  for (uint64_t s = seed;; ++s) {
    if (seeds >= 0 && static_cast<long>(s - seed) >= seeds) break;
    if (seconds >= 0 && elapsed() >= seconds) break;
    FailsafeSimulation sim(s);
    const std::vector<SimStep> plan = sim.generate(steps);
    const SimRunResult r = sim.run(plan, known);
    ++runs;
    total_steps += r.steps;
    total_frames += r.frames;
    sim_seconds += r.sim_seconds;
    for (const auto& [id, n] : r.known_failures) known_hits[id] += n;
    for (const auto& [row, n] : r.coverage) coverage[row] += n;
    if (known_example.empty()) known_example = r.known_example;
    if (runs == 1) {
      // The same seed gives the same frames, byte for byte.
      const SimRunResult again = sim.run(plan, known);
      total_steps += again.steps;
      if (again.digest != r.digest || again.frames != r.frames) {
        std::printf("FAILURE seed %llu: not deterministic: digest %016llx then %016llx\n",
                    static_cast<unsigned long long>(s), static_cast<unsigned long long>(r.digest),
                    static_cast<unsigned long long>(again.digest));
        ++failures;
        failure_texts.push_back("seed " + std::to_string(s) + ": digest differs between runs");
      }
    }
    if (!quiet)
      std::printf("seed %llu: %zu steps, %llu frames, %.0f s simulated, digest %016llx%s\n",
                  static_cast<unsigned long long>(s), r.steps,
                  static_cast<unsigned long long>(r.frames), r.sim_seconds,
                  static_cast<unsigned long long>(r.digest), r.failure ? ", FAILED" : "");
    else if (elapsed() - last_print >= 10) {
      last_print = elapsed();
      std::printf("%.0f s: %llu seeds, %llu steps, %llu failures\n", elapsed(),
                  static_cast<unsigned long long>(runs),
                  static_cast<unsigned long long>(total_steps),
                  static_cast<unsigned long long>(failures));
    }
    std::fflush(stdout);
    if (!r.failure) continue;
    ++failures;
    printFailure(s, *r.failure);
    failure_texts.push_back("seed " + std::to_string(s) + " step " +
                            std::to_string(r.failure->step) + " " + r.failure->invariant + ": " +
                            r.failure->message);
    const std::vector<SimStep> shrunk = sim.shrink(plan, r.failure->invariant, known);
    std::printf("  shrunk to %zu steps:\n", shrunk.size());
    for (const SimStep& st : shrunk) std::printf("    %s\n", st.text().c_str());
    if (!cases.empty()) {
      SimCase c;
      c.seed = s;
      c.invariant = r.failure->invariant;
      c.known = known;
      c.note = r.failure->message + "\n" + sim.describe();
      c.steps = shrunk;
      const std::string path =
          cases + "/seed_" + std::to_string(s) + "_" + r.failure->invariant + ".case";
      std::string error;
      if (writeSimCase(path, c, &error))
        std::printf("  written to %s\n", path.c_str());
      else
        std::printf("  %s\n", error.c_str());
    }
    std::fflush(stdout);
  }
  const double wall = elapsed();
  // Coverage (docs/simulation.md): every row hit, the required ones first, with the misses.
  std::vector<std::string> missing;
  std::printf("\n| coverage | hits |\n|---|---|\n");
  for (const std::string& row : simRequiredCoverage()) {
    const auto it = coverage.find(row);
    const uint64_t n = it == coverage.end() ? 0 : it->second;
    std::printf("| %s | %llu%s |\n", row.c_str(), static_cast<unsigned long long>(n),
                n == 0 ? " (required: NONE)" : "");
    if (n == 0) missing.push_back(row);
  }
  const auto& required = simRequiredCoverage();
  for (const auto& [row, n] : coverage)
    if (std::find(required.begin(), required.end(), row) == required.end())
      std::printf("| %s | %llu (not required) |\n", row.c_str(),
                  static_cast<unsigned long long>(n));
  if (require_coverage && !missing.empty()) {
    ++failures;
    std::string rows;
    for (const std::string& m : missing) rows += (rows.empty() ? "" : ", ") + m;
    std::printf("FAILURE coverage: %zu required row(s) never hit: %s\n", missing.size(),
                rows.c_str());
    failure_texts.push_back("coverage: never hit: " + rows);
  }
  std::printf(
      "\n| runs | steps | frames | simulated s | wall s | steps/min | failures |\n"
      "|---|---|---|---|---|---|---|\n| %llu | %llu | %llu | %.0f | %.1f | %.0f | %llu |\n",
      static_cast<unsigned long long>(runs), static_cast<unsigned long long>(total_steps),
      static_cast<unsigned long long>(total_frames), sim_seconds, wall,
      wall > 0 ? total_steps / wall * 60 : 0.0, static_cast<unsigned long long>(failures));
  for (const auto& [id, n] : known_hits)
    std::printf("known open defect %s failed %llu time(s) (counted, not failed)\n", id.c_str(),
                static_cast<unsigned long long>(n));
  if (!known_example.empty()) std::printf("  first: %s\n", known_example.c_str());
  if (!junit.empty()) {
    std::ofstream out(junit);
    out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuite name=\"failsafe_simulation\" "
        << "tests=\"1\" failures=\"" << (failures ? 1 : 0) << "\" time=\"" << wall << "\">\n"
        << "  <testcase classname=\"failsafe_simulation\" name=\"seeds_from_" << seed
        << "\" time=\"" << wall << "\">\n";
    if (failures) {
      std::string all;
      for (const std::string& t : failure_texts) all += t + "\n";
      out << "    <failure message=\"" << xml(failure_texts.front()) << "\">" << xml(all)
          << "</failure>\n";
    }
    out << "    <system-out>" << runs << " seeds, " << total_steps << " steps, "
        << (wall > 0 ? static_cast<long>(total_steps / wall * 60) : 0) << " steps/min";
    for (const auto& [id, n] : known_hits) out << "; known open " << id << ": " << n;
    out << "</system-out>\n  </testcase>\n</testsuite>\n";
  }
  return failures ? 1 : 0;
}
