// A device's callers' commands on their way to the bus (failsafe/device_commands.h): what is
// queued, what goes on the wire (byte exact, scripted transport), who learns the outcome, and
// what the fail-safe then expects of each channel. The bus runs by hand, in the order queued, as
// the bus thread would run them.
#include <gtest/gtest.h>

#include <deque>

#include "device_fixtures.h"
#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/failsafe/device_commands.h"

using namespace modbus_rtu_driver;

namespace {

struct Commands : ::testing::Test {
  ManualClock clock;
  ScriptedTransport bus;
  BusScheduler scheduler{bus, {}, clock};
  LcRelay8 board{devtest::config("lc_relay8", 255)};
  DeviceFailsafe failsafe{board, scheduler, clock};
  DeviceCommands commands{board, failsafe, scheduler};

  // The bus runs by hand: no thread, no poll (none is added), one step at a time.
  Commands() {
    scheduler.addDevice(board.name());
    scheduler.startStepping();
  }
  // Jobs still queued fail unsent as the bus stops: before the commands they call into go.
  ~Commands() override { scheduler.stop(); }
  // Runs the bus until the job whose future is `f` has run; its outcome.
  Result runUntilDone(std::future<Result>& f) {
    EXPECT_TRUE(f.valid());
    if (!f.valid()) return Result::failure(ErrorKind::kInvalidArgument, "nothing queued");
    Clock::time_point next;
    while (f.wait_for(std::chrono::seconds(0)) != std::future_status::ready)
      if (!scheduler.step(&next)) {
        ADD_FAILURE() << "the job never ran";
        return Result::failure(ErrorKind::kInvalidArgument, "never ran");
      }
    return f.get();
  }
  size_t queued() const { return scheduler.queuedJobs(); }
  Expectation expected(uint8_t channel) {
    return failsafe.intents().expected(channel, clock.now());
  }
};

}  // namespace

TEST_F(Commands, ARefusedWriteQueuesNothingAndTellsTheCallerWhy) {
  std::future<Result> f = commands.write({8}, {true});
  ASSERT_TRUE(f.valid());
  const Result r = f.get();
  EXPECT_EQ(r.error, ErrorKind::kInvalidArgument);
  EXPECT_NE(r.message.find("channel: 8 is outside 0-7"), std::string::npos) << r.message;
  bool told = false;
  commands.command(9, true, {0, [&](const Result& w) {
                               told = true;
                               EXPECT_EQ(w.error, ErrorKind::kInvalidArgument);
                             }});
  EXPECT_TRUE(told);
  EXPECT_EQ(queued(), 0u);
  EXPECT_EQ(bus.executed(), 0);
}

TEST_F(Commands, CommandsThatCameMeanwhileGoOutInOneWriteAndEachLearnsItsOutcome) {
  std::vector<Result> outcomes;
  auto done = [&](const Result& r) { outcomes.push_back(r); };
  std::future<Result> job = commands.command(1, true, {0, done});
  commands.command(2, true, {0, done});
  commands.command(1, false, {0, done});  // newer than the first for channel 1
  ASSERT_EQ(queued(), 1u) << "one job for the commands";
  std::vector<uint8_t> written_channels;
  std::vector<bool> written_states;
  commands.setWritten([&](const std::vector<uint8_t>& c, const std::vector<bool>& s) {
    written_channels = c;
    written_states = s;
  });
  bus.expectEcho(toHex(encodeRequest(Request::writeMultipleCoils(255, 1, {false, true}))));
  EXPECT_TRUE(runUntilDone(job).ok());
  ASSERT_EQ(outcomes.size(), 3u);
  for (const Result& r : outcomes) EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(written_channels, (std::vector<uint8_t>{1, 2}));
  EXPECT_EQ(written_states, (std::vector<bool>{false, true}));
  // The fail-safe holds the channels at what the device confirmed.
  EXPECT_EQ(expected(1).kind, Expectation::Kind::kLevel);
  EXPECT_FALSE(expected(1).level);
  EXPECT_EQ(expected(2).kind, Expectation::Kind::kLevel);
  EXPECT_TRUE(expected(2).level);
  // A command after that job ran queues the next one.
  commands.command(3, true, {0, done});
  EXPECT_EQ(queued(), 1u);
  EXPECT_SCRIPT_DONE(bus);
  // That job fails unsent as the bus stops, and tells `done`: before `outcomes` goes.
  scheduler.stop();
}

TEST_F(Commands, CommandsMergedIntoAWriteWithoutAnAnswerAreEachToldItFailedInArrivalOrder) {
  std::vector<int> order;
  std::vector<Result> outcomes;
  auto doneAs = [&](int n) {
    return [&, n](const Result& r) {
      order.push_back(n);
      outcomes.push_back(r);
    };
  };
  std::future<Result> job = commands.command(3, true, {0, doneAs(0)});
  commands.command(4, true, {0, doneAs(1)});
  commands.command(3, false, {0, doneAs(2)});
  ASSERT_EQ(queued(), 1u);
  EXPECT_TRUE(order.empty()) << "nobody is told before the write went out";
  // One FC15 of channels 3-4 (3 off, the newest for it; 4 on), then silence, and silence again
  // for the read back.
  bus.expect(toHex(encodeRequest(Request::writeMultipleCoils(255, 3, {false, true}))));
  bus.expect(toHex(encodeRequest(Request::readCoils(255, 0, 8))));
  EXPECT_FALSE(runUntilDone(job).ok());
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2}));
  for (const Result& r : outcomes) EXPECT_FALSE(r.ok());
  EXPECT_EQ(expected(3).kind, Expectation::Kind::kAny);
  EXPECT_EQ(expected(4).kind, Expectation::Kind::kAny);
  EXPECT_SCRIPT_DONE(bus);
}

TEST_F(Commands, AWriteWithoutAnAnswerIsNotConfirmedToItsCallerNorTheFailsafe) {
  bool written = false;
  commands.setWritten(
      [&](const std::vector<uint8_t>&, const std::vector<bool>&) { written = true; });
  std::future<Result> first = commands.write({4}, {false});
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleCoil(255, 4, false))));
  EXPECT_TRUE(runUntilDone(first).ok());
  ASSERT_TRUE(written);
  ASSERT_EQ(expected(4).kind, Expectation::Kind::kLevel);
  written = false;
  std::future<Result> second = commands.write({4}, {true});
  // Silent, and silent again for the read back that might have confirmed it.
  bus.expect(toHex(encodeRequest(Request::writeSingleCoil(255, 4, true))));
  bus.expect(toHex(encodeRequest(Request::readCoils(255, 0, 8))));
  const Result r = runUntilDone(second);
  EXPECT_FALSE(r.ok());
  EXPECT_FALSE(written);
  // The device may have done it: the channel is whatever the next poll shows.
  EXPECT_EQ(expected(4).kind, Expectation::Kind::kAny);
  EXPECT_SCRIPT_DONE(bus);
}

TEST_F(Commands, ATimedCommandConfirmedIsTheCallersWithItsEndAndFinalLevel) {
  int after = 0;
  std::future<Result> confirmed = commands.timed(
      TimedIntent{5, true, false, 2.0}, [&](Transport& t) { return board.pulse(t, 5, true, 2.0); },
      [&](Transport&) { ++after; });
  const Request flash =
      Request::writeMultipleRegisters(255, LcRelay8::flashRegister(5), {LcRelay8::kFlashClose, 20});
  bus.expectEcho(toHex(encodeRequest(flash)));
  EXPECT_TRUE(runUntilDone(confirmed).ok());
  EXPECT_EQ(after, 1);
  EXPECT_EQ(expected(5).kind, Expectation::Kind::kLevel);
  EXPECT_TRUE(expected(5).level) << "on during the flash-close";
  clock.advance(std::chrono::seconds(3));
  EXPECT_EQ(expected(5).kind, Expectation::Kind::kLevel);
  EXPECT_FALSE(expected(5).level) << "off after it";
  // Not confirmed: `after` does not run, the channel may show either level.
  std::future<Result> refused = commands.timed(
      TimedIntent{6, true, false, 2.0}, [&](Transport& t) { return board.pulse(t, 6, true, 2.0); },
      [&](Transport&) { ++after; });
  const Request flash6 =
      Request::writeMultipleRegisters(255, LcRelay8::flashRegister(6), {LcRelay8::kFlashClose, 20});
  bus.expect(toHex(encodeRequest(flash6)), toHex(encodeException(255, 0x10, 4)));
  EXPECT_FALSE(runUntilDone(refused).ok());
  EXPECT_EQ(after, 1);
  EXPECT_SCRIPT_DONE(bus);
}

TEST_F(Commands, ATimedCommandAWriteWhoseAnswerWasLostMayHaveReplacedIsNoLongerKept) {
  std::vector<std::vector<TimedIntent>> told;
  failsafe.setTimedChanged(
      [&](const std::vector<TimedIntent>& running) { told.push_back(running); });
  std::future<Result> flash = commands.timed(
      TimedIntent{5, true, false, 2.0}, [&](Transport& t) { return board.pulse(t, 5, true, 2.0); },
      [](Transport&) {});
  bus.expectEcho(toHex(encodeRequest(Request::writeMultipleRegisters(
      255, LcRelay8::flashRegister(5), {LcRelay8::kFlashClose, 20}))));
  EXPECT_TRUE(runUntilDone(flash).ok());
  ASSERT_EQ(told.size(), 1u);
  ASSERT_EQ(told[0].size(), 1u);
  EXPECT_EQ(told[0][0].channel, 5);
  // A plain write on that channel during the flash: no answer, and no read back (a read could
  // not tell the flash's level from the write's: docs/ros_api.md).
  std::future<Result> plain = commands.write({5}, {true});
  bus.expect(toHex(encodeRequest(Request::writeSingleCoil(255, 5, true))));
  const Result not_confirmed = runUntilDone(plain);
  EXPECT_FALSE(not_confirmed.ok());
  EXPECT_NE(not_confirmed.message.find("may still drive output 5"), std::string::npos)
      << not_confirmed.message;
  // The flash may have been replaced: the next node must not resume it (the first poll after
  // its end plus the slack decides the channel here).
  ASSERT_EQ(told.size(), 2u);
  EXPECT_TRUE(told[1].empty());
  EXPECT_SCRIPT_DONE(bus);
}
