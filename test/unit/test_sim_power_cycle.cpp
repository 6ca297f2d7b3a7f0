// The simulator's power_cycle of one device by address (or #index): that board restarts
// (pending settings apply, outputs off), the others keep their state.
#include <gtest/gtest.h>

#include "modbus_rtu_driver/sim/simulator.h"
#include "test_sim_helpers.h"

using namespace modbus_rtu_driver;
using namespace modbus_rtu_driver::simtest;

TEST(SimPowerCycleOne, OnlyTheNamedDeviceRestarts) {
  ScratchDir dir;
  auto sim = started(dir, {{"lc_relay8", 255}, {"ld58a08", 1}, {"yespeed_pdu", 2}});
  ASSERT_EQ(sim->command("set 255 coil 0 1 1"), "ok");
  ASSERT_EQ(sim->command("set 1 coil 5 1"), "ok");
  ASSERT_EQ(sim->command("set 255 holding_register 1001 4"), "ok");  // 19200 once powered again
  ASSERT_EQ(sim->command("set 1 holding_register 254 2"), "ok");     // 4800 once powered again
  ASSERT_EQ(sim->command("set 2 coil 0 1"), "ok");

  ASSERT_EQ(sim->command("power_cycle 1"), "ok");
  EXPECT_EQ(sim->command("info"),
            "ok #0:lc_relay8:255:9600:N #1:ld58a08:1:4800:N #2:yespeed_pdu:2:9600:N");
  EXPECT_EQ(sim->command("get 1 coil 5"), "ok 0") << "the cycled board's outputs went off";
  EXPECT_EQ(sim->command("get 255 coil 0 2"), "ok 1 1") << "the others kept theirs";
  EXPECT_EQ(sim->command("get 2 coil 0"), "ok 1");

  ASSERT_EQ(sim->command("power_cycle #2"), "ok");  // by config index
  EXPECT_EQ(sim->command("get 2 coil 0"), "ok 0");
  EXPECT_EQ(sim->command("get 255 coil 0 2"), "ok 1 1");
}

TEST(SimPowerCycleOne, AnUnknownDeviceIsAnErrorAndNothingRestarts) {
  ScratchDir dir;
  auto sim = started(dir, {{"lc_relay8", 255}});
  ASSERT_EQ(sim->command("set 255 coil 0 1"), "ok");
  EXPECT_EQ(sim->command("power_cycle 9"), "error no device '9' (#index or address; see info)");
  EXPECT_EQ(sim->command("get 255 coil 0"), "ok 1");
}
