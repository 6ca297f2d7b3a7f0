// The bus thread: writes before polls, fair polling, offline devices backed off, reconnects.
// Every test runs on a ManualClock: time moves only when the test jumps it to the moment the
// idle bus thread wakes, or when a transaction on the FakeBus takes its time. Counts and times
// are exact and no test sleeps; real-time deadlines are only a safety net against hangs.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <thread>

#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/core/bus/rate_meter.h"
#include "wait_for.h"

using namespace modbus_rtu_driver;
using namespace std::chrono_literals;

namespace {

constexpr auto kSafetyNet = 10s;  // real time; only reached when something hangs

// Answers every request after `latency` of clock time; slaves listed in `dead` time out (after
// `timeout`). Transactions that would start at or after the hold time wait, asleep on the
// clock, until the hold moves: how a test catches a bus that never idles, or keeps a
// transaction on the bus while it queues writes. It starts held: nothing goes on the bus
// before the test runs the clock (runUntil) or releases it.
class FakeBus : public Transport {
 public:
  explicit FakeBus(ManualClock& clock) : clock_(clock), hold_from_(clock.now()) {}

  Clock::duration latency = 2ms, timeout = 20ms;
  std::atomic<bool> up{true};
  std::atomic<int> connects{0};
  std::set<uint8_t> dead;
  std::mutex m;
  std::vector<std::string> log;                  // "<slave>r" / "<slave>w" per transaction
  std::vector<Clock::time_point> started;        // when each of them started
  std::vector<Clock::time_point> connect_times;  // when each connect() was tried

  Result execute(const Request& r) override {
    waitWhileHeld();
    bool is_dead;
    {
      std::lock_guard<std::mutex> lock(m);
      log.push_back(std::to_string(r.slave) + (isReadFunction(r.function) ? "r" : "w"));
      started.push_back(clock_.now());
      is_dead = dead.count(r.slave) > 0;
    }
    if (!up) return Result::failure(ErrorKind::kIo, "port gone");
    clock_.advance(is_dead ? timeout : latency);
    if (is_dead) return Result::failure(ErrorKind::kTimeout, "no reply");
    return Result::success({1});
  }
  bool connect(std::string* error) override {
    {
      std::lock_guard<std::mutex> lock(m);
      connect_times.push_back(clock_.now());
    }
    ++connects;
    if (!up && error) *error = "cannot open /dev/fake: No such file or directory";
    connected_ = up.load();
    return up;
  }
  bool connected() const override { return connected_; }
  void disconnect() override { connected_ = false; }
  std::atomic<bool> connected_{true};

  void holdFrom(Clock::time_point t) {
    {
      std::lock_guard<std::mutex> lock(gate_m_);
      hold_from_ = t;
    }
    clock_.notifyAll(gate_cv_);
  }
  void hold() { holdFrom(clock_.now()); }  // the next transaction waits
  void release() { holdFrom(Clock::time_point::max()); }

 private:
  void waitWhileHeld() {
    std::unique_lock<std::mutex> lock(gate_m_);
    while (clock_.now() >= hold_from_) clock_.waitUntil(lock, gate_cv_, Clock::time_point::max());
  }

  ManualClock& clock_;
  std::mutex gate_m_;
  std::condition_variable gate_cv_;
  Clock::time_point hold_from_;
};

BusScheduler::Job read(uint8_t slave) {
  return [slave](Transport& t) { return t.execute(Request::readCoils(slave, 0, 8)); };
}

BusScheduler::Job writeCoil(uint8_t slave) {
  return [slave](Transport& t) { return t.execute(Request::writeSingleCoil(slave, 0, true)); };
}

class BusSchedulerTest : public ::testing::Test {
 protected:
  ~BusSchedulerTest() override {
    bus.release();
    scheduler.reset();
  }

  BusScheduler& make(const BusScheduler::Options& o = {}) { return make(bus, o); }
  BusScheduler& make(Transport& transport, BusScheduler::Options o = {}) {
    scheduler = std::make_unique<BusScheduler>(transport, std::move(o), clock);
    return *scheduler;
  }

  // Runs the bus until clock time t0 + `t`: each time its thread is idle (asleep on the
  // clock), time jumps to when it wakes. What is due before that time has run on return; what
  // is due at or after it has not started (a bus that never idles is held by the FakeBus).
  ::testing::AssertionResult runUntil(Clock::duration t) {
    const Clock::time_point end = t0 + t;
    bus.holdFrom(end);
    for (;;) {
      if (!clock.awaitSleepers(1, kSafetyNet))
        return ::testing::AssertionFailure() << "the bus thread did not go idle";
      const Clock::time_point next = clock.nextDeadline();
      if (next >= end) return ::testing::AssertionSuccess();
      clock.advanceTo(next);
    }
  }

  // Clock times (ms after t0) at which transactions to `slave` started.
  std::vector<long> startsOf(uint8_t slave) {
    std::lock_guard<std::mutex> lock(bus.m);
    std::vector<long> out;
    for (size_t i = 0; i < bus.log.size(); ++i)
      if (bus.log[i].substr(0, bus.log[i].size() - 1) == std::to_string(slave))
        out.push_back(ms(bus.started[i]));
    return out;
  }
  long ms(Clock::time_point t) const {
    return static_cast<long>(std::chrono::duration_cast<std::chrono::milliseconds>(t - t0).count());
  }

  ManualClock clock;
  const Clock::time_point t0 = clock.now();
  FakeBus bus{clock};
  std::unique_ptr<BusScheduler> scheduler;
};

bool ready(std::future<Result>& f) {
  return f.wait_for(kSafetyNet) == std::future_status::ready;
}

}  // namespace

TEST_F(BusSchedulerTest, WritesGoAheadOfPolls) {
  BusScheduler& s = make();
  std::atomic<int> polls{0};
  s.addPoll("a", 200.0, read(1), [&](const Result&) { ++polls; });
  s.start();
  ASSERT_TRUE(runUntil(50ms));
  EXPECT_EQ(polls.load(), 10);  // 0, 5, ..., 45 ms
  // Five writes queued together while the bus is busy (the first one is held on it).
  bus.hold();
  std::vector<std::future<Result>> writes;
  for (int i = 0; i < 5; ++i) writes.push_back(s.submit("a", writeCoil(1)));
  bus.release();
  for (auto& w : writes) {
    ASSERT_TRUE(ready(w));
    EXPECT_TRUE(w.get().ok());
  }
  s.stop();
  // No poll ran between them, though the one due at 50 ms was due during them.
  std::lock_guard<std::mutex> lock(bus.m);
  auto first = std::find(bus.log.begin(), bus.log.end(), "1w");
  ASSERT_EQ(first - bus.log.begin(), 10);
  ASSERT_GE(bus.log.end() - first, 5);
  EXPECT_TRUE(std::all_of(first, first + 5, [](const std::string& e) { return e == "1w"; }));
  EXPECT_GT(polls.load(), 3);
}

TEST_F(BusSchedulerTest, PollRatesAreSharedAndAchievedRateIsReported) {
  BusScheduler& s = make();
  s.addPoll("fast", 50.0, read(1), nullptr);
  s.addPoll("slow", 10.0, read(2), nullptr);
  s.start();
  ASSERT_TRUE(runUntil(1500ms));
  const DeviceHealth fast = s.health("fast"), slow = s.health("slow");
  EXPECT_EQ(fast.polls_ok, 75u);  // due at 0, 20, ..., 1480 ms
  EXPECT_EQ(slow.polls_ok, 15u);  // due at 0, 100, ..., 1400 ms
  // 74 intervals between the first reply (2 ms) and the last one (1482 ms).
  EXPECT_NEAR(fast.achieved_poll_rate, 50.0, 1e-9);
  EXPECT_TRUE(fast.online);
  EXPECT_FALSE(fast.rate_overrun);
  EXPECT_FALSE(slow.rate_overrun);
}

TEST_F(BusSchedulerTest, DevicesWithTheSameRateAreEachPolledAtIt) {
  BusScheduler& s = make();
  for (uint8_t a = 1; a <= 3; ++a) s.addPoll("d" + std::to_string(a), 10.0, read(a), nullptr);
  s.start();
  ASSERT_TRUE(runUntil(1500ms));
  for (uint8_t a = 1; a <= 3; ++a) {
    const DeviceHealth h = s.health("d" + std::to_string(a));
    EXPECT_EQ(h.polls_ok, 15u) << int(a);
    EXPECT_NEAR(h.achieved_poll_rate, 10.0, 1e-9) << int(a);
    // One after the other at each period, in the same order every time.
    std::vector<long> expected;
    for (long k = 0; k < 15; ++k) expected.push_back(k * 100 + 2L * (a - 1));
    EXPECT_EQ(startsOf(a), expected) << int(a);
  }
}

TEST_F(BusSchedulerTest, ARateTheBusCannotCarryIsReported) {
  bus.latency = 20ms;  // at most 50 transactions per second
  BusScheduler& s = make();
  s.addPoll("greedy", 500.0, read(1), nullptr);
  s.start();
  ASSERT_TRUE(runUntil(1500ms));
  const DeviceHealth h = s.health("greedy");
  EXPECT_EQ(h.polls_ok, 75u);  // back to back
  EXPECT_TRUE(h.rate_overrun);
  EXPECT_NEAR(h.achieved_poll_rate, 50.0, 1e-9);
  EXPECT_LT(h.achieved_poll_rate, 100.0);
}

// docs/troubleshooting.md "the other devices keep their poll rates", docs/share.md: a device
// that answers is polled ahead of devices that gave no reply to their last request, so silent
// devices (each poll a whole timeout) delay its poll by the one transaction in progress, also
// before their backoff has grown. Stop 42: three silent devices with longer periods, always
// overdue, claimed more priority than a 10 Hz board that answered, which went unpolled for
// 7 s, and the safe write it owed with it (case open_30min_held_relays_out0_late).
TEST_F(BusSchedulerTest, SilentDevicesDelayAnAnsweringDevicesPollByOneTransactionAtMost) {
  bus.dead = {2, 3, 4};
  bus.timeout = 100ms;
  BusScheduler& s = make();
  s.addPoll("answers", 10.0, read(1), nullptr);
  s.addPoll("silent2", 2.0, read(2), nullptr);
  s.addPoll("silent3", 5.0, read(3), nullptr);
  s.addPoll("silent4", 5.0, read(4), nullptr);
  s.start();
  ASSERT_TRUE(runUntil(3000ms));
  const std::vector<long> polls = startsOf(1);
  ASSERT_GE(polls.size(), 2u);
  // From when each silent device has failed once (their first polls, due at 0, go by rate:
  // nothing is known of them before).
  for (size_t i = 1; i < polls.size(); ++i) {
    EXPECT_LE(polls[i] - std::max(polls[i - 1], 302L), 100 + 100)
        << "poll " << i << " at " << polls[i] << " ms";
  }
  EXPECT_GE(polls.size(), 15u);  // a third of the bus at most goes to the silent ones' timeouts
  for (uint8_t a = 2; a <= 4; ++a) EXPECT_GE(startsOf(a).size(), 2u) << int(a);  // still probed
}

// docs/share.md: once offline, a silent device's probes are spaced by the backoff and go in
// their turn, also on a bus the answering devices keep busy: a device that answers again is
// seen within the backoff (5 s), not a backoff plus a wait behind the others (stop 42's
// simulation: a PDU back on a busy bus was first probed 7 s later, its owed safe write with it).
TEST_F(BusSchedulerTest, AnOfflineDevicesProbesKeepTheirBackoffOnABusyBus) {
  bus.dead = {3};
  bus.latency = 10ms;  // the two answering devices ask for the whole bus
  BusScheduler& s = make();
  s.addPoll("a", 50.0, read(1), nullptr);
  s.addPoll("b", 50.0, read(2), nullptr);
  s.addPoll("silent", 5.0, read(3), nullptr);
  s.start();
  ASSERT_TRUE(runUntil(30s));
  const std::vector<long> probes = startsOf(3);
  ASSERT_GE(probes.size(), 6u);
  EXPECT_FALSE(s.health("silent").online);
  // The backoff (at most 5 s; before it is offline, as long waiting for the answering devices),
  // then its turn among polls as late as the longest period (200 ms), its timeout, a poll.
  for (size_t i = 1; i < probes.size(); ++i)
    EXPECT_LE(probes[i] - probes[i - 1], 5000 + 200 + 20 + 10)
        << "probe " << i << " at " << probes[i];
}

// docs/share.md: a bus that cannot carry the rates is shared in turn. Stop 42: devices with
// longer periods, each always more than the fast device's period late, claimed more priority
// than it and took the whole bus (here: 2 polls in 3 s); a 10 Hz board back from offline went
// unpolled for 2 s (case open_30min_held_relays_out4_late). Every device late by the longest
// period or more has the same claim, and the one served least recently goes first.
TEST_F(BusSchedulerTest, AnOverloadedBusPollsEveryDeviceInTurn) {
  bus.latency = 70ms;  // 14 transactions a second; the slow devices alone ask for 15
  BusScheduler& s = make();
  s.addPoll("fast", 10.0, read(1), nullptr);
  for (uint8_t a = 2; a <= 4; ++a) s.addPoll("slow" + std::to_string(a), 5.0, read(a), nullptr);
  s.start();
  ASSERT_TRUE(runUntil(3000ms));
  for (uint8_t a = 1; a <= 4; ++a) {
    const std::vector<long> polls = startsOf(a);
    ASSERT_GE(polls.size(), 2u) << int(a);
    for (size_t i = 1; i < polls.size(); ++i)  // the three others in between, at most
      EXPECT_LE(polls[i] - polls[i - 1], 4 * 70) << int(a) << ": poll " << i << " at " << polls[i];
  }
  for (uint8_t a = 2; a <= 4; ++a)  // it asks for twice as many: it gets no fewer
    EXPECT_GE(startsOf(1).size(), startsOf(a).size()) << int(a);
}

// The claim of a late poll is capped at the longest period, but at most 1 s: a fast device that
// fell behind (here: silent for 2.5 s, every poll a timeout) catches up on the bus without
// holding an on-time device back by more than that, even with a device polled every 50 s.
TEST_F(BusSchedulerTest, AFastDeviceCatchingUpHoldsTheOthersBackByOneSecondAtMost) {
  BusScheduler::Options o;
  o.offline_after = 1000;  // no backoff: its schedule falls behind while it times out
  bus.dead = {1};
  bus.timeout = 100ms;  // each silent poll puts it 80 ms further behind
  bus.latency = 15ms;   // and it catches up 5 ms a poll
  BusScheduler& s = make(o);
  s.addPoll("fast", 50.0, read(1), nullptr);
  s.addPoll("steady", 5.0, read(2), nullptr);
  s.addPoll("rare", 0.02, read(3), nullptr);
  s.start();
  ASSERT_TRUE(runUntil(2500ms));
  {
    std::lock_guard<std::mutex> lock(bus.m);
    bus.dead.clear();
  }
  ASSERT_TRUE(runUntil(6000ms));
  const std::vector<long> steady = startsOf(2);
  ASSERT_GE(steady.size(), 2u);
  long worst = 0;
  for (size_t i = 1; i < steady.size(); ++i) worst = std::max(worst, steady[i] - steady[i - 1]);
  EXPECT_LE(worst, 200 + 1000) << "the steady device waited " << worst << " ms";
  EXPECT_GE(startsOf(1).size(), 100u);  // the fast one caught up meanwhile
}

TEST_F(BusSchedulerTest, AnOfflineDeviceIsBackedOffAndDoesNotStallOthers) {
  bus.dead = {2};
  BusScheduler::Options o;
  o.offline_after = 2;
  o.backoff_initial = 0.2;
  o.backoff_max = 0.4;
  BusScheduler& s = make(o);
  s.addPoll("alive", 20.0, read(1), nullptr);
  s.addPoll("dead", 20.0, read(2), nullptr);
  s.start();
  ASSERT_TRUE(runUntil(1500ms));
  const DeviceHealth alive = s.health("alive"), dead = s.health("dead");
  EXPECT_FALSE(dead.online);
  EXPECT_EQ(dead.consecutive_failures, 5u);
  EXPECT_EQ(dead.last_error, "no reply");
  // Two failures (each a 20 ms timeout) at its rate, then probes after 200, 400 and 400 ms
  // (the maximum) of backoff, counted from the end of the failed probe.
  EXPECT_EQ(startsOf(2), (std::vector<long>{2, 52, 72 + 200, 292 + 400, 712 + 400}));
  EXPECT_EQ(dead.polls_failed, 5u);  // a dead device polled at 20 Hz would be tried 30 times
  EXPECT_EQ(alive.polls_ok, 30u);    // all of them: due at 0, 50, ..., 1450 ms
  EXPECT_FALSE(alive.rate_overrun);
  // It comes back by itself, at the next probe.
  {
    std::lock_guard<std::mutex> lock(bus.m);
    bus.dead.clear();
  }
  ASSERT_TRUE(runUntil(1532ms));
  EXPECT_FALSE(s.health("dead").online);
  ASSERT_TRUE(runUntil(2300ms));
  EXPECT_TRUE(s.health("dead").online);
  EXPECT_EQ(startsOf(2).at(5), 1132 + 400);
  EXPECT_EQ(s.health("dead").consecutive_failures, 0u);
}

TEST_F(BusSchedulerTest, ExceptionsDoNotMakeADeviceOffline) {
  struct Refusing : FakeBus {
    using FakeBus::FakeBus;
    Result execute(const Request&) override {
      return Result::failure(ErrorKind::kException, "illegal data address", 2);
    }
  } refusing{clock};
  BusScheduler& s = make(refusing);
  s.addPoll("d", 100.0, read(1), nullptr);
  s.start();
  ASSERT_TRUE(runUntil(200ms));
  EXPECT_TRUE(s.health("d").online);
  EXPECT_EQ(s.health("d").polls_failed, 20u);  // every one, at its rate
  EXPECT_EQ(s.health("d").consecutive_failures, 0u);
  s.stop();  // before `refusing` goes
}

TEST_F(BusSchedulerTest, ReconnectsAfterThePortGoesAway) {
  BusScheduler::Options o;
  o.reconnect_initial = 0.05;
  o.reconnect_max = 0.1;
  BusScheduler& s = make(o);
  s.addPoll("a", 50.0, read(1), nullptr);
  s.start();
  ASSERT_TRUE(runUntil(100ms));
  EXPECT_EQ(s.health("a").polls_ok, 5u);
  bus.up = false;  // the next transaction (the poll at 100 ms) fails with an I/O error
  ASSERT_TRUE(runUntil(400ms));
  EXPECT_FALSE(s.connected());
  EXPECT_NE(s.connectionError().find("/dev/fake"), std::string::npos);
  // Writes fail at once while the port is gone, naming why.
  auto w = s.submit("a", read(1));
  ASSERT_TRUE(ready(w));
  const Result r = w.get();
  EXPECT_EQ(r.error, ErrorKind::kNotConnected);
  EXPECT_NE(r.message.find("/dev/fake"), std::string::npos) << r.message;
  EXPECT_EQ(s.health("a").writes_refused, 1u);
  bus.up = true;
  ASSERT_TRUE(runUntil(800ms));
  EXPECT_TRUE(s.connected());
  bus.release();
  auto again = s.submit("a", read(1));
  ASSERT_TRUE(ready(again));
  EXPECT_TRUE(again.get().ok());
  s.stop();
  // Right away, then after 50 ms, then every 100 ms (the maximum) until it opens.
  std::vector<long> tries;
  {
    std::lock_guard<std::mutex> lock(bus.m);
    for (auto t : bus.connect_times) tries.push_back(ms(t));
  }
  EXPECT_EQ(tries, (std::vector<long>{100, 150, 250, 350, 450}));
  EXPECT_EQ(bus.connects.load(), 5);
}

// The node logs "port open again after ..." and "back online after ...": the scheduler keeps
// how long each outage lasted, on its clock.
TEST_F(BusSchedulerTest, APortOpenAgainSaysAfterHowLong) {
  BusScheduler::Options o;
  o.reconnect_initial = 0.05;
  o.reconnect_max = 0.1;
  BusScheduler& s = make(o);
  s.addPoll("a", 50.0, read(1), nullptr);
  s.start();
  ASSERT_TRUE(runUntil(100ms));
  EXPECT_EQ(s.portReopens().count, 0u) << "the first open is no reopening";
  bus.up = false;  // the poll at 100 ms fails: the port is lost then
  ASSERT_TRUE(runUntil(400ms));
  bus.up = true;  // reopened by the try at 450 ms
  ASSERT_TRUE(runUntil(800ms));
  EXPECT_TRUE(s.connected());
  EXPECT_EQ(s.portReopens().count, 1u);
  EXPECT_NEAR(s.portReopens().last_outage_seconds, 0.35, 1e-9);
  s.stop();
}

TEST_F(BusSchedulerTest, ADeviceBackOnlineSaysAfterHowLong) {
  bus.dead = {2};
  BusScheduler::Options o;
  o.offline_after = 2;
  o.backoff_initial = 0.2;
  o.backoff_max = 0.4;
  BusScheduler& s = make(o);
  s.addPoll("dead", 20.0, read(2), nullptr);
  s.start();
  ASSERT_TRUE(runUntil(1500ms));
  EXPECT_FALSE(s.health("dead").online);  // since its second timeout ended
  {
    std::lock_guard<std::mutex> lock(bus.m);
    bus.dead.clear();
  }
  ASSERT_TRUE(runUntil(2300ms));
  EXPECT_TRUE(s.health("dead").online);
  const std::vector<long> starts = startsOf(2);
  const long offline_at = starts.at(1) + 20;  // the second timeout's end
  const long back_at =  // the first probe after the device woke, and its 2 ms of latency
      *std::find_if(starts.begin(), starts.end(), [](long t) { return t >= 1500; }) + 2;
  EXPECT_NEAR(s.health("dead").last_offline_seconds, (back_at - offline_at) / 1000.0, 1e-9);
}

TEST_F(BusSchedulerTest, StopFailsWhatIsStillQueued) {
  BusScheduler& s = make();
  bus.release();
  s.start();
  // The first job is on the bus until stop() has begun (a submit then fails at once); the four
  // behind it never run.
  std::promise<void> on_bus;
  std::vector<std::future<Result>> jobs;
  jobs.push_back(s.submit("a", [&](Transport& t) {
    on_bus.set_value();
    waitFor(
        [&] {
          auto probe = s.submit("a", read(1));
          return probe.wait_for(0s) == std::future_status::ready &&
                 probe.get().message == "bus stopped";
        },
        std::chrono::duration<double>(kSafetyNet).count());
    return t.execute(Request::readCoils(1, 0, 8));
  }));
  for (int i = 0; i < 4; ++i) jobs.push_back(s.submit("a", read(1)));
  ASSERT_EQ(on_bus.get_future().wait_for(kSafetyNet), std::future_status::ready);
  s.stop();
  int stopped = 0;
  for (auto& j : jobs) {
    ASSERT_TRUE(ready(j));
    const Result r = j.get();
    if (!r.ok()) {
      EXPECT_EQ(r.message, "bus stopped");
      ++stopped;
    }
  }
  EXPECT_EQ(stopped, 4);
  EXPECT_EQ(s.submit("a", read(1)).get().message, "bus stopped");
  std::lock_guard<std::mutex> lock(bus.m);
  EXPECT_EQ(bus.log, std::vector<std::string>{"1r"});  // only the job that was on the bus
}

TEST_F(BusSchedulerTest, AnOverloadedBusIsSharedInTurn) {
  // 16 devices each asking for more than the bus carries: none may take more than its turn,
  // whatever its place in the list, also after the schedule gives up catching up (3 s behind).
  bus.latency = 2ms;
  BusScheduler& s = make();
  for (uint8_t a = 1; a <= 16; ++a) {
    s.addDevice("d" + std::to_string(a));
    s.addPoll("d" + std::to_string(a), 1000.0, read(a), nullptr);
  }
  s.start();
  ASSERT_TRUE(runUntil(4500ms));
  uint64_t least = UINT64_MAX, most = 0, total = 0;
  for (uint8_t a = 1; a <= 16; ++a) {
    const uint64_t n = s.health("d" + std::to_string(a)).polls_ok;
    least = std::min(least, n);
    most = std::max(most, n);
    total += n;
  }
  EXPECT_EQ(total, 2250u);  // back to back for 4.5 s
  EXPECT_GT(most, 20u);
  EXPECT_GE(least * 5, most * 4) << "fewest " << least << ", most " << most;
  EXPECT_LE(most - least, 1u) << "fewest " << least << ", most " << most;
}

TEST_F(BusSchedulerTest, AWriteWaitsForOneTransactionNotAWholePoll) {
  bus.latency = 30ms;
  BusScheduler& s = make();
  s.addDevice("slow");
  s.addPoll(
      "slow", 1.0,
      [](Transport& t) {
        for (int i = 0; i < 3; ++i) t.execute(Request::readCoils(1, 0, 8));
        return Result::success();
      },
      nullptr);
  bus.hold();  // the poll's first read stays on the bus
  s.start();
  ASSERT_TRUE(clock.awaitSleepers(1, kSafetyNet));
  ASSERT_EQ(clock.nextDeadline(), Clock::time_point::max());  // held, not waiting for time
  auto write = s.submit("other", writeCoil(2));
  bus.release();
  ASSERT_TRUE(ready(write));
  EXPECT_TRUE(write.get().ok());
  ASSERT_TRUE(runUntil(500ms));  // the rest of the poll
  s.stop();
  std::lock_guard<std::mutex> lock(bus.m);
  ASSERT_EQ(bus.log.size(), 4u);
  EXPECT_EQ(bus.log[0], "1r");
  EXPECT_EQ(bus.log[1], "2w") << "the write goes between the poll's transactions";
  EXPECT_EQ(bus.log[2], "1r");
  EXPECT_EQ(bus.log[3], "1r");
  EXPECT_EQ(ms(bus.started[1]), 30);  // right after the first read
}

// Shared requests (Modbus TCP clients of the share): after every write, ahead of every poll,
// also between a poll's transactions.
TEST_F(BusSchedulerTest, SharedRequestsGoAfterWritesAndAheadOfPolls) {
  bus.latency = 30ms;
  BusScheduler& s = make();
  s.addPoll(
      "slow", 1.0,
      [](Transport& t) {
        for (int i = 0; i < 3; ++i) t.execute(Request::readCoils(1, 0, 8));
        return Result::success();
      },
      nullptr);
  bus.hold();  // the poll's first read stays on the bus while everything else queues
  s.start();
  ASSERT_TRUE(clock.awaitSleepers(1, kSafetyNet));
  std::vector<std::promise<Result>> shared(2);
  std::atomic<int> shared_runs{0};
  auto submitShared = [&](uint8_t slave, std::promise<Result>& done) {
    s.submitShared(
        "",
        [&shared_runs, slave](Transport& t) {
          ++shared_runs;
          return t.execute(Request::readHoldingRegisters(slave, 0, 1));
        },
        [&done](const Result& r) { done.set_value(r); });
  };
  submitShared(3, shared[0]);
  auto w1 = s.submit("w", writeCoil(2));
  submitShared(4, shared[1]);
  auto w2 = s.submit("w", writeCoil(5));
  bus.release();
  for (auto& p : shared) {
    auto f = p.get_future();
    ASSERT_TRUE(ready(f));
    EXPECT_TRUE(f.get().ok());
  }
  ASSERT_TRUE(ready(w1));
  ASSERT_TRUE(ready(w2));
  ASSERT_TRUE(runUntil(500ms));  // the rest of the poll
  s.stop();
  EXPECT_EQ(shared_runs.load(), 2);
  std::lock_guard<std::mutex> lock(bus.m);
  EXPECT_EQ(bus.log, (std::vector<std::string>{"1r", "2w", "5w", "3r", "4r", "1r", "1r"}));
  EXPECT_EQ(ms(bus.started[3]), 90) << "right after the writes, inside the poll";
}

TEST_F(BusSchedulerTest, SharedRequestsAreRefusedWhileThePortIsClosed) {
  bus.up = false;
  bus.connected_ = false;
  BusScheduler::Options o;
  o.reconnect_initial = 0.05;
  BusScheduler& s = make(o);
  s.addDevice("d");
  s.start();
  ASSERT_TRUE(runUntil(10ms));
  std::promise<Result> done;
  std::atomic<int> runs{0};
  s.submitShared(
      "d",
      [&](Transport& t) {
        ++runs;
        return t.execute(Request::readCoils(1, 0, 8));
      },
      [&](const Result& r) { done.set_value(r); });
  auto f = done.get_future();
  ASSERT_TRUE(ready(f));
  const Result r = f.get();
  EXPECT_EQ(r.error, ErrorKind::kNotConnected);
  EXPECT_NE(r.message.find("/dev/fake"), std::string::npos) << r.message;
  EXPECT_EQ(runs.load(), 1);
  EXPECT_EQ(s.health("d").writes_refused, 1u);
  EXPECT_EQ(s.health("d").shared_failed, 0u);  // refused unsent: not a failure of the device
  s.stop();
  std::lock_guard<std::mutex> lock(bus.m);
  EXPECT_TRUE(bus.log.empty());
}

TEST_F(BusSchedulerTest, StopFailsSharedRequestsStillQueuedEachRunOnce) {
  BusScheduler& s = make();
  bus.release();
  s.start();
  std::promise<void> on_bus;
  auto first = s.submit("a", [&](Transport& t) {
    on_bus.set_value();
    waitFor(
        [&] {
          // Queued probes are answered later, at stop: the promise must outlive this lambda.
          auto probe = std::make_shared<std::promise<Result>>();
          auto f = probe->get_future();
          s.submitShared(
              "a", [](Transport& t) { return t.execute(Request::readCoils(1, 0, 8)); },
              [probe](const Result& r) { probe->set_value(r); });
          return f.wait_for(0s) == std::future_status::ready && f.get().message == "bus stopped";
        },
        std::chrono::duration<double>(kSafetyNet).count());
    return t.execute(Request::readCoils(1, 0, 8));
  });
  constexpr int kQueued = 4;
  std::vector<std::promise<Result>> done(kQueued);
  std::atomic<int> runs{0};
  for (auto& d : done)
    s.submitShared(
        "a",
        [&](Transport& t) {
          ++runs;
          return t.execute(Request::readCoils(2, 0, 8));
        },
        [&d](const Result& r) { d.set_value(r); });
  ASSERT_EQ(on_bus.get_future().wait_for(kSafetyNet), std::future_status::ready);
  s.stop();
  ASSERT_TRUE(ready(first));
  EXPECT_TRUE(first.get().ok());
  for (auto& d : done) {
    auto f = d.get_future();
    ASSERT_TRUE(ready(f));
    EXPECT_EQ(f.get().message, "bus stopped");
  }
  EXPECT_EQ(runs.load(), kQueued);  // each ran once, against the refusing transport
  std::lock_guard<std::mutex> lock(bus.m);
  EXPECT_EQ(bus.log, std::vector<std::string>{"1r"});
}

TEST(RateMeter, TheRateOfTheLastFiveSeconds) {
  RateMeter m;
  const auto t0 = std::chrono::steady_clock::time_point{} + std::chrono::hours(1);
  EXPECT_EQ(m.rate(), 0.0);
  m.record(t0);
  EXPECT_EQ(m.rate(), 0.0);  // one poll: no rate yet
  for (int i = 1; i <= 10; ++i) m.record(t0 + std::chrono::milliseconds(100 * i));
  EXPECT_NEAR(m.rate(), 10.0, 1e-9);
  // Slower from 1 s on: 5 s later only the 2 Hz polls are in the window.
  const auto t1 = t0 + std::chrono::seconds(1);
  for (int i = 1; i <= 12; ++i) m.record(t1 + std::chrono::milliseconds(500 * i));
  EXPECT_NEAR(m.rate(), 2.0, 1e-9);
  // A slow group alone: two polls 5 s apart are 0.2 Hz.
  RateMeter slow;
  slow.record(t0);
  slow.record(t0 + std::chrono::seconds(5));
  EXPECT_NEAR(slow.rate(), 0.2, 1e-9);
  slow.record(t0 + std::chrono::seconds(10));
  EXPECT_NEAR(slow.rate(), 0.2, 1e-9);
}

namespace {
// A line every request to which succeeds, logged as "<slave>r" (a read) or "<slave>w".
struct LoggingLine : Transport {
  std::vector<std::string> log;
  Result execute(const Request& r) override {
    log.push_back(std::to_string(r.slave) + (isReadFunction(r.function) ? "r" : "w"));
    return Result::success({0});
  }
};
}  // namespace

// Step mode (the deterministic simulation's): no thread; step() runs one thing on the caller's
// thread, writes ahead of polls, and otherwise says when the next poll falls due.
TEST(BusSchedulerStepMode, RunsOneThingPerStepOnTheCallersThread) {
  LoggingLine line;
  ManualClock clock;
  BusScheduler scheduler(line, {}, clock);
  scheduler.startStepping();
  const auto start = clock.now();
  scheduler.addPoll(
      "a", 10.0, [](Transport& t) { return t.execute(Request::readCoils(1, 0, 1)); }, nullptr);
  Clock::time_point next{};
  EXPECT_TRUE(scheduler.step(&next));  // the poll due now (the port is open)
  EXPECT_FALSE(scheduler.step(&next));
  EXPECT_EQ(next, start + 100ms);  // the next poll
  const std::thread::id caller = std::this_thread::get_id();
  std::thread::id ran_on;
  auto done = scheduler.submit("a", [&](Transport& t) {
    ran_on = std::this_thread::get_id();
    return t.execute(Request::writeSingleCoil(1, 0, true));
  });
  EXPECT_EQ(done.wait_for(0s), std::future_status::timeout);  // queued, not run
  EXPECT_TRUE(scheduler.step(&next));
  ASSERT_EQ(done.wait_for(0s), std::future_status::ready);
  EXPECT_TRUE(done.get().ok());
  EXPECT_EQ(ran_on, caller);
  EXPECT_EQ(line.log, (std::vector<std::string>{"1r", "1w"}));
  clock.advanceTo(next);
  EXPECT_TRUE(scheduler.step(&next));
  EXPECT_EQ(line.log.back(), "1r");
  scheduler.stop();
  EXPECT_FALSE(scheduler.step(&next));
  EXPECT_EQ(next, Clock::time_point::max());
}

// docs/failsafe.md "Timing", docs/ros_api.md: a device that gave no reply at all to its last
// request costs one transaction per job: the job stops at its first request that again gets
// none (a write is not read back), and the rest is not sent. A garbled reply or one that comes
// is an answer: the next job runs whole (its read back included).
TEST(BusSchedulerStepMode, AJobForASilentDeviceStopsAtItsFirstUnansweredRequest) {
  struct Line : Transport {
    std::vector<std::string> log;
    std::map<uint8_t, ErrorKind> fails;  // slave -> how each request to it fails
    Result execute(const Request& r) override {
      log.push_back(std::to_string(r.slave) + (isReadFunction(r.function) ? "r" : "w"));
      auto f = fails.find(r.slave);
      if (f != fails.end()) return Result::failure(f->second, "fails");
      return Result::success({0});
    }
  } line;
  ManualClock clock;
  BusScheduler scheduler(line, {}, clock);
  scheduler.startStepping();
  // A write and the read that would confirm it, as the device classes do after a lost answer.
  auto writeThenReadBack = [](Transport& t) {
    Result r = t.execute(Request::writeSingleCoil(1, 0, true));
    if (r.ok()) return r;
    Result back = t.execute(Request::readCoils(1, 0, 8));
    return back.ok() ? back : r;
  };
  auto runJob = [&]() {
    auto done = scheduler.submit("a", writeThenReadBack);
    Clock::time_point next{};
    EXPECT_TRUE(scheduler.step(&next));
    EXPECT_EQ(done.wait_for(0s), std::future_status::ready);
    return done.get();
  };
  line.fails[1] = ErrorKind::kTimeout;
  // The device answered before: the whole job runs (the write, then its read back).
  EXPECT_EQ(runJob().error, ErrorKind::kTimeout);
  EXPECT_EQ(line.log, (std::vector<std::string>{"1w", "1r"}));
  // Its last request got no reply: the next job stops at its write.
  line.log.clear();
  const Result second = runJob();
  EXPECT_EQ(second.error, ErrorKind::kTimeout);
  EXPECT_EQ(line.log, (std::vector<std::string>{"1w"}));
  // A garbled reply is an answer (the device is there): the read back goes, and the job after
  // it runs whole.
  line.fails[1] = ErrorKind::kCrc;
  line.log.clear();
  runJob();
  EXPECT_EQ(line.log, (std::vector<std::string>{"1w", "1r"}));
  line.fails[1] = ErrorKind::kTimeout;
  line.log.clear();
  runJob();
  EXPECT_EQ(line.log, (std::vector<std::string>{"1w", "1r"}));
  // A poll with no reply marks the device too; one that answers clears it. (The device is
  // offline by now: its polls wait out the backoff.)
  scheduler.addPoll(
      "a", 10.0, [](Transport& t) { return t.execute(Request::readCoils(1, 0, 1)); }, nullptr);
  auto runPoll = [&] {
    Clock::time_point next{};
    while (!scheduler.step(&next)) clock.advanceTo(next);
  };
  line.fails.erase(1);
  runPoll();  // answers
  line.fails[1] = ErrorKind::kTimeout;
  runPoll();  // no reply
  line.log.clear();
  runJob();
  EXPECT_EQ(line.log, (std::vector<std::string>{"1w"}));
  line.fails.erase(1);
  runPoll();  // answers
  line.fails[1] = ErrorKind::kTimeout;
  line.log.clear();
  runJob();
  EXPECT_EQ(line.log, (std::vector<std::string>{"1w", "1r"}));
  scheduler.stop();
}

// docs/share.md: a poll overdue by a whole period of its device goes before the next queued
// job, and the queued jobs then get one transaction of it each. Its first request went after
// one queued job (stop 56: a silent board's write went ahead of a returning PDU's overdue poll,
// and with it that PDU's owed safe write: case held_safe_late_after_port_failure_and_broadcast).
TEST(BusSchedulerStepMode, AnOverduePollSendsItsFirstRequestBeforeTheNextQueuedJob) {
  LoggingLine line;
  ManualClock clock;
  BusScheduler scheduler(line, {}, clock);
  scheduler.startStepping();
  scheduler.addPoll(
      "a", 10.0,
      [](Transport& t) {
        Result r = t.execute(Request::readCoils(1, 0, 1));
        return r.ok() ? t.execute(Request::readHoldingRegisters(1, 0, 1)) : r;
      },
      nullptr);
  Clock::time_point next{};
  ASSERT_TRUE(scheduler.step(&next));  // the first poll, due at once
  line.log.clear();
  clock.advanceTo(clock.now() + 250ms);  // overdue by more than its period (100 ms)
  std::vector<std::future<Result>> writes;
  for (int i = 0; i < 3; ++i)
    writes.push_back(scheduler.submit(
        "b", [](Transport& t) { return t.execute(Request::writeSingleCoil(2, 0, true)); }));
  ASSERT_TRUE(scheduler.step(&next));  // the overdue poll, one queued write between its requests
  EXPECT_EQ(line.log, (std::vector<std::string>{"1r", "2w", "1r"}));
  // It is not overdue by a whole period any more: the queued writes go first again.
  ASSERT_TRUE(scheduler.step(&next));
  ASSERT_TRUE(scheduler.step(&next));
  EXPECT_EQ(line.log, (std::vector<std::string>{"1r", "2w", "1r", "2w", "2w"}));
  for (auto& w : writes) EXPECT_TRUE(w.get().ok());
  scheduler.stop();
}

// docs/share.md: while a device's late-reply guard holds its next request, queued shared
// requests to other devices that end before the guard does use the line; nothing else moves.
namespace {

// A line whose slaves may be under a late-reply guard until a time of the manual clock; every
// request takes 5 ms and may take up to `line_seconds` (its longest transaction).
struct GuardedLine : Transport {
  explicit GuardedLine(ManualClock& c) : clock(c) {}
  Result execute(const Request& r) override {
    log.push_back(std::to_string(r.slave) + (isReadFunction(r.function) ? "r" : "w"));
    clock.advance(5ms);
    return Result::success({0});
  }
  double guardLeft(const Request& next) const override {
    const auto g = guard_until.find(next.slave);
    if (g == guard_until.end() || g->second <= clock.now()) return 0;
    return std::chrono::duration<double>(g->second - clock.now()).count();
  }
  double lineSeconds(const Request& /*request*/) const override { return line_seconds; }
  ManualClock& clock;
  std::map<uint8_t, Clock::time_point> guard_until;
  double line_seconds = 0.03;
  std::vector<std::string> log;
};

template <class Line = GuardedLine>
struct GuardFillOn {
  GuardFillOn() : line(clock), scheduler(line, {}, clock) { scheduler.startStepping(); }
  void guard(uint8_t slave, std::chrono::milliseconds left) {
    line.guard_until[slave] = clock.now() + left;
  }
  std::future<Result> write(const std::string& device, uint8_t slave) {
    return scheduler.submit(device, [slave](Transport& t) {
      return t.execute(Request::writeSingleCoil(slave, 0, true));
    });
  }
  void share(const std::string& device, const Request& r) {
    scheduler.submitShared(
        device, [r](Transport& t) { return t.execute(r); },
        [this](const Result& result) { answers.push_back(result); }, 0, r);
  }
  void runAll() {
    Clock::time_point next{};
    while (scheduler.step(&next)) {
    }
  }
  ManualClock clock;
  Line line;
  BusScheduler scheduler;
  std::vector<Result> answers;  // of the shared requests, in order
};
using GuardFill = GuardFillOn<>;

}  // namespace

TEST(BusSchedulerGuardTime, ASharedReadOfAnotherDeviceGoesWithinTheGuard) {
  GuardFill f;
  f.guard(1, 100ms);
  auto w = f.write("a", 1);
  f.share("b", Request::readHoldingRegisters(2, 0, 1));
  f.share("b", Request::readHoldingRegisters(2, 1, 1));
  f.runAll();
  EXPECT_TRUE(w.get().ok());
  EXPECT_EQ(f.answers.size(), 2u);
  EXPECT_EQ(f.line.log, (std::vector<std::string>{"2r", "2r", "1w"}));
  EXPECT_EQ(f.scheduler.ranInGuards(), 2u);
}

// Each only while it still ends before the guard does: the guarded request starts no later.
TEST(BusSchedulerGuardTime, OnlyWhatEndsBeforeTheGuardGoesFirst) {
  GuardFill f;
  f.guard(1, 40ms);  // 30 ms fits once: after it (5 ms), 35 ms are left, then 30 after another
  auto w = f.write("a", 1);
  for (int i = 0; i < 4; ++i) f.share("b", Request::readHoldingRegisters(2, 0, 1));
  f.runAll();
  EXPECT_TRUE(w.get().ok());
  EXPECT_EQ(f.line.log, (std::vector<std::string>{"2r", "2r", "2r", "1w", "2r"}));
  EXPECT_EQ(f.scheduler.ranInGuards(), 3u);
}

TEST(BusSchedulerGuardTime, ATransactionLongerThanTheGuardWaits) {
  GuardFill f;
  f.guard(1, 100ms);
  f.line.line_seconds = 0.15;
  auto w = f.write("a", 1);
  f.share("b", Request::readHoldingRegisters(2, 0, 1));
  f.runAll();
  EXPECT_TRUE(w.get().ok());
  EXPECT_EQ(f.line.log, (std::vector<std::string>{"1w", "2r"}));
  EXPECT_EQ(f.scheduler.ranInGuards(), 0u);
}

// The guarded device's own requests, a broadcast, a guarded device's, or one whose device has a
// ROS write queued: none goes ahead.
TEST(BusSchedulerGuardTime, NothingElseGoesAhead) {
  GuardFill f;
  f.guard(1, 100ms);
  f.guard(3, 100ms);
  auto w1 = f.write("a", 1);
  auto w4 = f.write("d", 4);
  f.share("a", Request::readHoldingRegisters(1, 0, 1));  // the guarded device itself
  f.share("", Request::writeSingleCoil(0, 0, true));     // a broadcast
  f.share("c", Request::readHoldingRegisters(3, 0, 1));  // guarded too
  f.share("d", Request::readHoldingRegisters(4, 0, 1));  // its device has a write queued
  f.line.line_seconds = 0.03;
  f.runAll();
  EXPECT_TRUE(w1.get().ok());
  EXPECT_TRUE(w4.get().ok());
  // Once device d's write has gone, its read may use slave 1's guard.
  EXPECT_EQ(f.line.log, (std::vector<std::string>{"1w", "4w", "4r", "1r", "0w", "3r"}));
  EXPECT_EQ(f.scheduler.ranInGuards(), 1u);
}

// A shared request of a device keeps its place behind that device's earlier one, which did not
// fit; another device's that fits goes.
TEST(BusSchedulerGuardTime, ADevicesSharedRequestsKeepTheirOrder) {
  struct Line : GuardedLine {
    using GuardedLine::GuardedLine;
    double lineSeconds(const Request& r) const override { return r.slave == 2 ? 0.5 : 0.03; }
  };
  ManualClock clock;
  Line line(clock);
  BusScheduler s(line, {}, clock);
  s.startStepping();
  line.guard_until[1] = clock.now() + 100ms;
  auto w =
      s.submit("a", [](Transport& t) { return t.execute(Request::writeSingleCoil(1, 0, true)); });
  for (const Request& r : {Request::readHoldingRegisters(2, 0, 1), Request::readCoils(2, 0, 1),
                           Request::readHoldingRegisters(5, 0, 1)})
    s.submitShared(
        "", [r](Transport& t) { return t.execute(r); }, nullptr, 0, r);
  Clock::time_point next{};
  while (s.step(&next)) {
  }
  EXPECT_TRUE(w.get().ok());
  EXPECT_EQ(line.log, (std::vector<std::string>{"5r", "1w", "2r", "2r"}));
  EXPECT_EQ(s.ranInGuards(), 1u);
}

// docs/share.md: a shared read goes within the guard when one attempt of it fits, and gets as
// many attempts as end before the guard does; a read whose answer they lost gets its remaining
// retries after the guarded request, never more attempts in all than the retries allow.
namespace {

// Slave 2 loses the answers of its first `lost` attempts; one attempt takes 5 ms and may take
// up to 30 ms, a transaction up to 30 ms per attempt (1 + `retries`).
struct RetryingLine : GuardedLine {
  using GuardedLine::GuardedLine;
  Result execute(const Request& r) override { return executeAttempts(r, 0, -1); }
  Result executeAttempts(const Request& r, int first, int most) override {
    if (r.slave == 2) firsts.push_back(first);
    for (int attempt = first;; ++attempt) {
      GuardedLine::execute(r);
      if (r.slave != 2 || attempt >= lost) return Result::success({0});
      Result lost_answer = Result::failure(ErrorKind::kTimeout, "no answer");
      if (attempt >= retries) return lost_answer;
      lost_answer.retry_owed = most >= 0 && attempt + 1 - first >= most;
      if (lost_answer.retry_owed) return lost_answer;
    }
  }
  double attemptSeconds(const Request& /*request*/) const override { return 0.03; }
  double lineSeconds(const Request& /*request*/) const override { return 0.03 * (1 + retries); }
  int retries = 1, lost = 1;
  std::vector<int> firsts;  // the first attempt of each call for slave 2
};

}  // namespace

TEST(BusSchedulerGuardTime, AReadGoesWhenOneAttemptFitsAndItsRetryAfterTheGuardedRequest) {
  GuardFillOn<RetryingLine> f;
  // 34 ms: the first attempt fits (30), then 29 ms are left: the retry does not.
  f.guard(1, 34ms);
  auto w = f.write("a", 1);
  f.share("b", Request::readHoldingRegisters(2, 0, 1));
  f.runAll();
  EXPECT_TRUE(w.get().ok());
  EXPECT_EQ(f.line.log, (std::vector<std::string>{"2r", "1w", "2r"}));
  EXPECT_EQ(f.line.firsts, (std::vector<int>{0, 1})) << "the retry is attempt 1, not a new read";
  ASSERT_EQ(f.answers.size(), 1u) << "one answer, after the retry";
  EXPECT_TRUE(f.answers[0].ok()) << f.answers[0].message;
  EXPECT_EQ(f.scheduler.ranInGuards(), 1u);
}

// A read that no attempt gets an answer to ends with the link's retries spent, also when the
// guard cut it short: 1 + retries attempts in all.
TEST(BusSchedulerGuardTime, AReadCutShortNeverGetsMoreAttemptsThanItsRetries) {
  GuardFillOn<RetryingLine> f;
  f.line.lost = 10;  // never answered
  f.line.retries = 2;
  f.guard(1, 64ms);  // two attempts fit (60), the third does not
  auto w = f.write("a", 1);
  f.share("b", Request::readHoldingRegisters(2, 0, 1));
  f.runAll();
  EXPECT_TRUE(w.get().ok());
  // Two attempts fit the guard's 64 ms; they take 10, and the third fits the 54 left: all three
  // go before the write, the answer lost in each, and no fourth.
  EXPECT_EQ(f.line.log, (std::vector<std::string>{"2r", "2r", "2r", "1w"}));
  EXPECT_EQ(f.line.firsts, (std::vector<int>{0, 2}));
  ASSERT_EQ(f.answers.size(), 1u);
  EXPECT_EQ(f.answers[0].error, ErrorKind::kTimeout);
  EXPECT_FALSE(f.answers[0].retry_owed);
}

// A poll's request waits on the guard too: the shared read goes inside the poll, before it.
TEST(BusSchedulerGuardTime, APollsGuardedRequestLetsASharedReadGoFirst) {
  GuardFill f;
  f.scheduler.addPoll(
      "a", 10.0,
      [&f](Transport& t) {
        f.share("b", Request::readHoldingRegisters(2, 0, 1));  // comes while the poll runs
        f.guard(1, 100ms);
        return t.execute(Request::readCoils(1, 0, 1));
      },
      nullptr);
  Clock::time_point next{};
  EXPECT_TRUE(f.scheduler.step(&next));
  EXPECT_EQ(f.line.log, (std::vector<std::string>{"2r", "1r"}));
  EXPECT_EQ(f.answers.size(), 1u);
}

// docs/share.md: on a bus the polls alone fill (every poll a period late), the polls are not
// starved by a queued request: it goes first, before the next overdue poll (issue 52: an
// overdue poll before each client's read made the share's reads later, the polls no more
// frequent). Once the queued jobs have held the line a whole period, an overdue poll goes first.
TEST(BusSchedulerStepMode, OnABusThePollsFillAQueuedRequestGoesBeforeTheOverduePolls) {
  struct SlowLine : Transport {
    explicit SlowLine(ManualClock& c) : clock(c) {}
    Result execute(const Request& r) override {
      log.push_back(std::to_string(r.slave) + (isReadFunction(r.function) ? "r" : "w"));
      clock.advance(20ms);  // each transaction takes two periods of the polls below
      return Result::success({0});
    }
    ManualClock& clock;
    std::vector<std::string> log;
  };
  ManualClock clock;
  SlowLine line(clock);
  BusScheduler scheduler(line, {}, clock);
  scheduler.startStepping();
  for (uint8_t a : {1, 2})
    scheduler.addPoll(
        "d" + std::to_string(a), 100.0,
        [a](Transport& t) { return t.execute(Request::readCoils(a, 0, 1)); }, nullptr);
  Clock::time_point next{};
  for (int i = 0; i < 6; ++i) ASSERT_TRUE(scheduler.step(&next));  // polls, each overdue
  line.log.clear();
  auto write = scheduler.submit(
      "c", [](Transport& t) { return t.execute(Request::writeSingleCoil(3, 0, true)); });
  ASSERT_TRUE(scheduler.step(&next));
  EXPECT_EQ(line.log, std::vector<std::string>{"3w"}) << "an overdue poll went first";
  EXPECT_TRUE(write.get().ok());
  // That write held the line for two periods of the polls: with a backlog queued now, an
  // overdue poll goes before each queued write.
  line.log.clear();
  std::vector<std::future<Result>> writes;
  for (int i = 0; i < 3; ++i)
    writes.push_back(scheduler.submit(
        "c", [](Transport& t) { return t.execute(Request::writeSingleCoil(3, 0, true)); }));
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(scheduler.step(&next));
  EXPECT_EQ(line.log, (std::vector<std::string>{"1r", "3w", "2r", "3w"}));
  scheduler.stop();
}
