// The fail-safe's deterministic simulation (docs/simulation.md): its regression cases replay as
// recorded, a seed repeats its frames byte for byte, and a bounded run of seeds finds no failure
// beyond the known open defects (simKnownOpen()). The long runs: scripts/simulate.sh, and 60 s
// in scripts/test.sh.
#include <dirent.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "modbus_rtu_driver/simulation/failsafe_simulation.h"

using namespace modbus_rtu_driver;

namespace {

std::vector<std::string> caseFiles() {
  const std::string dir = std::string(REPO_DIR) + "/test/data/simulation";
  std::vector<std::string> files;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string name = e->d_name;
      if (name.size() > 5 && name.substr(name.size() - 5) == ".case")
        files.push_back(dir + "/" + name);
    }
    closedir(d);
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

TEST(FailsafeSimulation, RegressionCasesReplayAsRecorded) {
  const auto files = caseFiles();
  ASSERT_FALSE(files.empty()) << "no test/data/simulation/*.case";
  for (const std::string& f : files) {
    SimCase c;
    std::string error;
    ASSERT_TRUE(readSimCase(f, &c, &error)) << error;
    const SimRunResult r = FailsafeSimulation(c.seed).run(c.steps, c.known);
    if (c.status == "fixed") {
      EXPECT_FALSE(r.failure) << f << ": fixed, but fails again: " << r.failure->invariant << " "
                              << r.failure->message;
    } else {
      // A known open defect: it must still fail the same way. When it passes, the defect was
      // fixed: mark the case "status fixed" and take its invariant out of simKnownOpen().
      ASSERT_TRUE(r.failure) << f << ": known open defect no longer fails: mark it fixed";
      EXPECT_EQ(r.failure->invariant, c.invariant) << f << ": " << r.failure->message;
    }
  }
}

TEST(FailsafeSimulation, ASeedRepeatsItsFramesByteForByte) {
  const FailsafeSimulation sim(7);
  const std::vector<SimStep> steps = sim.generate(1500);
  const SimRunResult a = sim.run(steps, simKnownOpen());
  const SimRunResult b = sim.run(steps, simKnownOpen());
  EXPECT_GT(a.frames, 1000u);
  EXPECT_EQ(a.frames, b.frames);
  EXPECT_EQ(a.digest, b.digest);
  // Another seed draws another bus and other steps.
  const FailsafeSimulation other(8);
  EXPECT_NE(other.run(other.generate(1500), simKnownOpen()).digest, a.digest);
}

TEST(FailsafeSimulation, StepsSurviveTheirText) {
  const FailsafeSimulation sim(3);
  for (const SimStep& s : sim.generate(200)) {
    const auto back = SimStep::parse(s.text());
    ASSERT_TRUE(back) << s.text();
    EXPECT_EQ(back->text(), s.text());
  }
  std::string error;
  EXPECT_FALSE(SimStep::parse("fly 1 2", &error));
  EXPECT_NE(error.find("unknown step 'fly'"), std::string::npos) << error;
}

// A bounded run (about 40 000 steps); the 60 s run is scripts/test.sh's.
TEST(FailsafeSimulation, BoundedRunFindsNoFailureBeyondTheKnownOnes) {
  uint64_t steps = 0;
  for (uint64_t seed = 1000; seed < 1020; ++seed) {
    const FailsafeSimulation sim(seed);
    const SimRunResult r = sim.run(sim.generate(2000), simKnownOpen());
    steps += r.steps;
    ASSERT_FALSE(r.failure) << "seed " << seed << " step " << r.failure->step << " "
                            << r.failure->invariant << ": " << r.failure->message
                            << " (replay: failsafe_simulation --seed " << seed << ")";
  }
  EXPECT_EQ(steps, 20u * 2000u);
}
