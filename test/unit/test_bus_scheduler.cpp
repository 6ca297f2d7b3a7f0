// The bus thread: writes before polls, fair polling, offline devices backed off, reconnects.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "modbus_rtu_driver/core/bus_scheduler.h"

using namespace modbus_rtu_driver;
using namespace std::chrono_literals;

namespace {

// Answers every request after `latency`; slaves listed in `dead` time out (after `timeout`).
class FakeBus : public Transport {
 public:
  std::chrono::milliseconds latency{2}, timeout{20};
  std::atomic<bool> up{true};
  std::atomic<int> connects{0};
  std::set<uint8_t> dead;
  std::mutex m;
  std::vector<std::string> log;

  Result execute(const Request& r) override {
    bool is_dead;
    {
      std::lock_guard<std::mutex> lock(m);
      log.push_back(std::to_string(r.slave) + (isReadFunction(r.function) ? "r" : "w"));
      is_dead = dead.count(r.slave) > 0;
    }
    if (!up) return Result::failure(ErrorKind::kIo, "port gone");
    std::this_thread::sleep_for(is_dead ? timeout : latency);
    if (is_dead) return Result::failure(ErrorKind::kTimeout, "no reply");
    return Result::success({1});
  }
  bool connect(std::string* error) override {
    ++connects;
    if (!up && error) *error = "cannot open /dev/fake: No such file or directory";
    connected_ = up.load();
    return up;
  }
  bool connected() const override { return connected_; }
  void disconnect() override { connected_ = false; }
  std::atomic<bool> connected_{true};
};

BusScheduler::Job read(uint8_t slave) {
  return [slave](Transport& t) { return t.execute(Request::readCoils(slave, 0, 8)); };
}

}  // namespace

TEST(BusScheduler, WritesGoAheadOfPolls) {
  FakeBus bus;
  BusScheduler s(bus);
  std::atomic<int> polls{0};
  s.addPoll("a", 200.0, read(1), [&](const Result&) { ++polls; });
  s.start();
  std::this_thread::sleep_for(50ms);
  std::vector<std::future<Result>> writes;
  for (int i = 0; i < 5; ++i)
    writes.push_back(s.submit(
        "a", [](Transport& t) { return t.execute(Request::writeSingleCoil(1, 0, true)); }));
  for (auto& w : writes) EXPECT_TRUE(w.get().ok());
  s.stop();
  // The five writes were queued together: no poll ran between them.
  std::lock_guard<std::mutex> lock(bus.m);
  auto first = std::find(bus.log.begin(), bus.log.end(), "1w");
  ASSERT_NE(first, bus.log.end());
  EXPECT_TRUE(std::all_of(first, first + 5, [](const std::string& e) { return e == "1w"; }));
  EXPECT_GT(polls.load(), 3);
}

TEST(BusScheduler, PollRatesAreSharedAndAchievedRateIsReported) {
  FakeBus bus;
  BusScheduler s(bus);
  s.addPoll("fast", 50.0, read(1), nullptr);
  s.addPoll("slow", 10.0, read(2), nullptr);
  s.start();
  std::this_thread::sleep_for(1500ms);
  s.stop();
  const DeviceHealth fast = s.health("fast"), slow = s.health("slow");
  // Generous bounds: a shared 2-core machine.
  EXPECT_GT(fast.polls_ok, 40u);
  EXPECT_LT(fast.polls_ok, 90u);
  EXPECT_GT(slow.polls_ok, 8u);
  EXPECT_LT(slow.polls_ok, 20u);
  EXPECT_GT(fast.achieved_poll_rate, 30.0);
  EXPECT_TRUE(fast.online);
}

TEST(BusScheduler, ARateTheBusCannotCarryIsReported) {
  FakeBus bus;
  bus.latency = 20ms;  // at most ~50 transactions per second
  BusScheduler s(bus);
  s.addPoll("greedy", 500.0, read(1), nullptr);
  s.start();
  std::this_thread::sleep_for(1500ms);
  const DeviceHealth h = s.health("greedy");
  s.stop();
  EXPECT_TRUE(h.rate_overrun);
  EXPECT_LT(h.achieved_poll_rate, 100.0);
}

TEST(BusScheduler, AnOfflineDeviceIsBackedOffAndDoesNotStallOthers) {
  FakeBus bus;
  bus.dead = {2};
  BusScheduler::Options o;
  o.offline_after = 2;
  o.backoff_initial = 0.2;
  o.backoff_max = 0.4;
  BusScheduler s(bus, o);
  s.addPoll("alive", 20.0, read(1), nullptr);
  s.addPoll("dead", 20.0, read(2), nullptr);
  s.start();
  std::this_thread::sleep_for(1500ms);
  const DeviceHealth alive = s.health("alive"), dead = s.health("dead");
  EXPECT_FALSE(dead.online);
  EXPECT_GE(dead.consecutive_failures, 2u);
  EXPECT_EQ(dead.last_error, "no reply");
  // Backed off: a dead device polled at 20 Hz would be tried ~30 times.
  EXPECT_LT(dead.polls_failed, 12u);
  EXPECT_GT(alive.polls_ok, 22u);  // ~30 expected at 20 Hz
  // It comes back by itself.
  {
    std::lock_guard<std::mutex> lock(bus.m);
    bus.dead.clear();
  }
  std::this_thread::sleep_for(800ms);
  EXPECT_TRUE(s.health("dead").online);
  s.stop();
}

TEST(BusScheduler, ExceptionsDoNotMakeADeviceOffline) {
  struct Refusing : FakeBus {
    Result execute(const Request&) override {
      return Result::failure(ErrorKind::kException, "illegal data address", 2);
    }
  } bus;
  BusScheduler s(bus);
  s.addPoll("d", 100.0, read(1), nullptr);
  s.start();
  std::this_thread::sleep_for(200ms);
  s.stop();
  EXPECT_TRUE(s.health("d").online);
  EXPECT_GT(s.health("d").polls_failed, 5u);
}

TEST(BusScheduler, ReconnectsAfterThePortGoesAway) {
  FakeBus bus;
  BusScheduler::Options o;
  o.reconnect_initial = 0.05;
  o.reconnect_max = 0.1;
  BusScheduler s(bus, o);
  s.addPoll("a", 50.0, read(1), nullptr);
  s.start();
  std::this_thread::sleep_for(100ms);
  bus.up = false;  // the next transaction fails with an I/O error
  std::this_thread::sleep_for(300ms);
  EXPECT_FALSE(s.connected());
  EXPECT_NE(s.connectionError().find("/dev/fake"), std::string::npos);
  // Writes fail fast while the port is gone, naming why.
  auto w = s.submit("a", read(1));
  ASSERT_EQ(w.wait_for(2s), std::future_status::ready);
  const Result r = w.get();
  EXPECT_EQ(r.error, ErrorKind::kNotConnected);
  bus.up = true;
  std::this_thread::sleep_for(400ms);
  EXPECT_TRUE(s.connected());
  EXPECT_TRUE(s.submit("a", read(1)).get().ok());
  s.stop();
  EXPECT_GE(bus.connects.load(), 2);
}

TEST(BusScheduler, StopFailsWhatIsStillQueued) {
  FakeBus bus;
  bus.latency = 100ms;
  BusScheduler s(bus);
  s.start();
  std::vector<std::future<Result>> jobs;
  for (int i = 0; i < 5; ++i) jobs.push_back(s.submit("a", read(1)));
  std::this_thread::sleep_for(50ms);
  s.stop();
  int stopped = 0;
  for (auto& j : jobs) {
    const Result r = j.get();
    if (!r.ok()) {
      EXPECT_EQ(r.message, "bus stopped");
      ++stopped;
    }
  }
  EXPECT_GE(stopped, 3);
  EXPECT_EQ(s.submit("a", read(1)).get().message, "bus stopped");
}

TEST(BusScheduler, AnOverloadedBusIsSharedInTurn) {
  // 16 devices each asking for more than the bus carries: none may take more than its turn,
  // whatever its place in the list, also after the schedule gives up catching up (3 s behind).
  FakeBus bus;
  bus.latency = 2ms;
  BusScheduler s(bus);
  for (uint8_t a = 1; a <= 16; ++a) {
    s.addDevice("d" + std::to_string(a));
    s.addPoll("d" + std::to_string(a), 1000.0, read(a), nullptr);
  }
  s.start();
  std::this_thread::sleep_for(4500ms);
  s.stop();
  uint64_t least = UINT64_MAX, most = 0;
  for (uint8_t a = 1; a <= 16; ++a) {
    const uint64_t n = s.health("d" + std::to_string(a)).polls_ok;
    least = std::min(least, n);
    most = std::max(most, n);
  }
  EXPECT_GT(most, 20u);
  EXPECT_GE(least * 5, most * 4) << "fewest " << least << ", most " << most;
}

TEST(BusScheduler, AWriteWaitsForOneTransactionNotAWholePoll) {
  FakeBus bus;
  bus.latency = 30ms;
  BusScheduler s(bus);
  s.addDevice("slow");
  s.addPoll(
      "slow", 1.0,
      [](Transport& t) {
        for (int i = 0; i < 3; ++i) t.execute(Request::readCoils(1, 0, 8));
        return Result::success();
      },
      nullptr);
  s.start();
  auto logged = [&] {
    std::lock_guard<std::mutex> lock(bus.m);
    return bus.log.size();
  };
  while (logged() == 0) std::this_thread::sleep_for(1ms);  // the poll's first read is on
  auto write = s.submit(
      "other", [](Transport& t) { return t.execute(Request::writeSingleCoil(2, 0, true)); });
  EXPECT_TRUE(write.get().ok());
  std::this_thread::sleep_for(100ms);  // the rest of the poll
  s.stop();
  std::lock_guard<std::mutex> lock(bus.m);
  ASSERT_GE(bus.log.size(), 4u);
  EXPECT_EQ(bus.log[0], "1r");
  EXPECT_EQ(bus.log[1], "2w") << "the write goes between the poll's transactions";
  EXPECT_EQ(bus.log[2], "1r");
  EXPECT_EQ(bus.log[3], "1r");
}
