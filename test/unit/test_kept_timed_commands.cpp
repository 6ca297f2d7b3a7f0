// The timed commands a node keeps for the next one (failsafe/kept_timed_commands.h): what the
// next node resumes, at which time, and what it drops.
#include <gtest/gtest.h>

#include "modbus_rtu_driver/failsafe/kept_timed_commands.h"

using namespace modbus_rtu_driver;

TEST(KeptTimedCommands, ANextNodeResumesWhatRunsWithTheSecondsLeft) {
  const std::vector<TimedIntent> running{TimedIntent(2, true, false, 3.0),
                                         TimedIntent(5, std::nullopt, false, -1.0)};
  const std::vector<KeptTimedCommand> kept = keepTimedCommands(running, 1000.0);
  // The continuous run on channel 5 has no end: the next node finds it (docs/failsafe.md,
  // "What restore writes": "not one a previous node started").
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept[0].channel, 2);
  EXPECT_EQ(kept[0].during, 1);
  EXPECT_DOUBLE_EQ(kept[0].ends, 1003.0);

  // The next node starts 1.25 s later.
  const std::vector<TimedIntent> resumed = resumeTimedCommands(kept, 1001.25, 8);
  ASSERT_EQ(resumed.size(), 1u);
  EXPECT_EQ(resumed[0].channel, 2);
  EXPECT_EQ(resumed[0].during, std::optional<bool>(true));
  EXPECT_FALSE(resumed[0].after);
  EXPECT_DOUBLE_EQ(resumed[0].seconds, 1.75);
}

TEST(KeptTimedCommands, ABurstKeepsAnyLevelUntilItsEnd) {
  const std::vector<KeptTimedCommand> kept =
      keepTimedCommands({TimedIntent(4, std::nullopt, false, 2.0)}, 50.0);
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept[0].during, -1);  // any level: the device toggles it
  const std::vector<TimedIntent> resumed = resumeTimedCommands(kept, 51.0, 8);
  ASSERT_EQ(resumed.size(), 1u);
  EXPECT_FALSE(resumed[0].during.has_value());
  EXPECT_DOUBLE_EQ(resumed[0].seconds, 1.0);
}

TEST(KeptTimedCommands, OneThatEndedWhileNoNodeRanOrNamesNoOutputIsDropped) {
  std::vector<KeptTimedCommand> kept(3);
  kept[0].channel = 1;
  kept[0].ends = 10.0;  // ended: the first poll shows its end
  kept[1].channel = 4;  // a device with 4 outputs has no channel 4
  kept[1].ends = 50.0;
  kept[2].channel = 3;
  kept[2].during = 0;
  kept[2].after = true;
  kept[2].ends = 12.5;
  const std::vector<TimedIntent> resumed = resumeTimedCommands(kept, 10.0, 4);
  ASSERT_EQ(resumed.size(), 1u);
  EXPECT_EQ(resumed[0].channel, 3);
  EXPECT_EQ(resumed[0].during, std::optional<bool>(false));
  EXPECT_TRUE(resumed[0].after);
  EXPECT_DOUBLE_EQ(resumed[0].seconds, 2.5);
}
