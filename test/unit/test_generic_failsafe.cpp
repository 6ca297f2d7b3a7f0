// A generic device's fail-safe (failsafe/generic_failsafe.h) on a scheduler in step mode over a
// scripted transport (byte exact): each safe value written and read back, the report and the
// status naming the values, and a write the silent device never got made again once it
// answers, but not one it refused.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "device_fixtures.h"
#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/core/config/signal.h"
#include "modbus_rtu_driver/failsafe/generic_failsafe.h"

using namespace modbus_rtu_driver;

namespace {

DeviceConfig drive() {
  DeviceConfig c = devtest::config("generic", 5);
  c.name = "drive";
  c.generic = parseSignalMap(
      YAML::Load(
          "signals:\n"
          "  - {name: speed, table: holding_register, address: 10, type: int16, scale: 0.1,\n"
          "     unit: rpm, writable: true, safe_value: -2.5}\n"
          "  - {name: run, table: coil, address: 3, type: bool, writable: true,\n"
          "     safe_value: 0}\n"),
      "devices/drive/", "");
  return c;
}

struct GenericSafe : ::testing::Test {
  GenericSafe() {
    scheduler.addDevice("drive");
    scheduler.startStepping();
    safe.setReportSink([this](const FailsafeReport& r) { reports.push_back(r); });
  }
  // Runs what the bus would run now, until nothing is left.
  void runBus() {
    Clock::time_point next;
    while (scheduler.step(&next)) {
    }
  }
  void expectSafeWrites(bool speed_answers) {
    const Request speed = Request::writeSingleRegister(5, 10, 0xFFE7);  // -25 x 0.1
    if (!speed_answers) {
      // Silent for the write and for the read back that would tell whether it was done.
      bus.expect(devtest::frame(speed));
      bus.expect(devtest::frame(Request::readHoldingRegisters(5, 10, 1)));
      return;
    }
    bus.expectEcho(devtest::frame(speed));
    bus.expect(devtest::frame(Request::readHoldingRegisters(5, 10, 1)),
               devtest::registersReply(5, 10, {0xFFE7}));
    bus.expectEcho(devtest::frame(Request::writeSingleCoil(5, 3, false)));
    const Request read_run = Request::readCoils(5, 3, 1);
    bus.expect(devtest::frame(read_run), toHex(encodeReply(read_run, {0})));
  }

  ManualClock clock;
  ScriptedTransport bus;
  BusScheduler scheduler{bus, {}, clock};
  GenericDevice device{drive()};
  GenericFailsafe safe{device, scheduler};
  std::vector<FailsafeReport> reports;
};

}  // namespace

TEST_F(GenericSafe, AReportNamesEachSafeValueAndTheStatusKeepsItUntilAUsersWrite) {
  ASSERT_TRUE(safe.hasSafeValues());
  expectSafeWrites(true);
  safe.applySafe(Trigger::kHeartbeat, "no message on /alive within 0.5 s");
  runBus();
  EXPECT_SCRIPT_DONE(bus);
  ASSERT_EQ(reports.size(), 1u);
  const FailsafeReport& r = reports[0];
  EXPECT_EQ(r.device, "drive");
  EXPECT_EQ(r.channels, (std::vector<std::string>{"speed", "run"}));
  EXPECT_EQ(r.values, (std::vector<double>{-2.5, 0.0}));
  EXPECT_EQ(r.states, (std::vector<bool>{true, false}));
  EXPECT_TRUE(r.confirmed);
  const std::string text = "heartbeat (no message on /alive within 0.5 s): speed -2.5 rpm, run off";
  EXPECT_EQ(safe.text(r), text);
  EXPECT_EQ(safe.status().events, 1u);
  EXPECT_EQ(safe.status().active, text);
  bus.expectEcho(devtest::frame(Request::writeSingleCoil(5, 3, true)));
  ASSERT_TRUE(safe.write(bus, 1, 1.0).ok());
  EXPECT_SCRIPT_DONE(bus);
  EXPECT_EQ(safe.status().active, "");
  EXPECT_EQ(safe.status().last_event, text);
}

TEST_F(GenericSafe, SafeValuesASilentDeviceNeverGotAreWrittenOnceItAnswers) {
  expectSafeWrites(false);
  safe.applySafe(Trigger::kShutdown, "node stops");
  runBus();
  EXPECT_SCRIPT_DONE(bus);
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_FALSE(reports[0].confirmed);
  EXPECT_NE(safe.text(reports[0]).find("; NOT confirmed: "), std::string::npos);
  // A poll it did not answer either: nothing is queued.
  safe.afterPoll(Result::failure(ErrorKind::kTimeout, "no reply"));
  EXPECT_EQ(scheduler.queuedJobs(), 0u);
  // It answers: every safe value again, once.
  safe.afterPoll(Result::success());
  EXPECT_EQ(scheduler.queuedJobs(), 1u);
  expectSafeWrites(true);
  runBus();
  EXPECT_SCRIPT_DONE(bus);
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_EQ(reports[1].trigger, Trigger::kRestart);
  EXPECT_TRUE(reports[1].confirmed);
  safe.afterPoll(Result::success());
  EXPECT_EQ(scheduler.queuedJobs(), 0u);
}

TEST_F(GenericSafe, AValueTheDeviceRefusedIsReportedNotWrittenAgainOnEveryPoll) {
  const Request speed = Request::writeSingleRegister(5, 10, 0xFFE7);
  bus.expect(devtest::frame(speed), toHex(encodeException(5, 0x06, 4)));
  bus.expectEcho(devtest::frame(Request::writeSingleCoil(5, 3, false)));
  const Request read_run = Request::readCoils(5, 3, 1);
  bus.expect(devtest::frame(read_run), toHex(encodeReply(read_run, {0})));
  safe.applySafe(Trigger::kHeartbeat, "lost");
  runBus();
  EXPECT_SCRIPT_DONE(bus);
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_FALSE(reports[0].confirmed);
  safe.afterPoll(Result::success());
  EXPECT_EQ(scheduler.queuedJobs(), 0u);
}

// docs/failsafe.md, "Generic devices": a signal set since the trigger is not written, neither
// by the owed write once the silent device answers nor by a safe write queued before the set.
TEST_F(GenericSafe, AnOwedSafeValueIsNotWrittenOverASetConfirmedSinceItsTrigger) {
  expectSafeWrites(false);
  safe.applySafe(Trigger::kHeartbeat, "lost");
  runBus();
  EXPECT_SCRIPT_DONE(bus);
  // It answers again; the user sets the speed (confirmed) before the next poll.
  bus.expectEcho(devtest::frame(Request::writeSingleRegister(5, 10, 300)));
  ASSERT_TRUE(safe.write(bus, 0, 30.0).ok());
  EXPECT_SCRIPT_DONE(bus);
  // The poll: only run is still owed.
  safe.afterPoll(Result::success());
  bus.expectEcho(devtest::frame(Request::writeSingleCoil(5, 3, false)));
  const Request read_run = Request::readCoils(5, 3, 1);
  bus.expect(devtest::frame(read_run), toHex(encodeReply(read_run, {0})));
  runBus();
  EXPECT_SCRIPT_DONE(bus);
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_EQ(reports[1].channels, (std::vector<std::string>{"run"}));
  EXPECT_TRUE(reports[1].confirmed);
  safe.afterPoll(Result::success());
  EXPECT_EQ(scheduler.queuedJobs(), 0u);
}

TEST_F(GenericSafe, ASetConfirmedBetweenTheTriggerAndItsSafeWriteKeepsItsValue) {
  safe.applySafe(Trigger::kHeartbeat, "lost");  // queued, not run yet
  bus.expectEcho(devtest::frame(Request::writeSingleCoil(5, 3, true)));
  ASSERT_TRUE(safe.write(bus, 1, 1.0).ok());  // the user's set reaches the bus first
  const Request speed = Request::writeSingleRegister(5, 10, 0xFFE7);  // speed only
  bus.expectEcho(devtest::frame(speed));
  bus.expect(devtest::frame(Request::readHoldingRegisters(5, 10, 1)),
             devtest::registersReply(5, 10, {0xFFE7}));
  runBus();
  EXPECT_SCRIPT_DONE(bus);
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_EQ(reports[0].channels, (std::vector<std::string>{"speed"}));
  // A later trigger writes both again.
  safe.applySafe(Trigger::kHeartbeat, "lost again");
  expectSafeWrites(true);
  runBus();
  EXPECT_SCRIPT_DONE(bus);
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_EQ(reports[1].channels, (std::vector<std::string>{"speed", "run"}));
}
