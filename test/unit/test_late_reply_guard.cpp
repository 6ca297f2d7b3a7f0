// The link's late-reply guard (docs/failsafe.md F90, docs/troubleshooting.md): a device's reply
// that comes within late_reply_guard after its request timed out is never taken as the reply to a
// different request. On the real Link's guard (Link::guardUntil, lineSettled, runAttempt) over the
// simulation's in-memory line, where time is a manual clock and a reply arrives exactly when the
// fault says: each case fails on the guard as it was before stop 56, when the simulation's late
// replies found it.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "modbus_rtu_driver/sim/sim_lc_relay8.h"
#include "modbus_rtu_driver/sim/sim_ld58a08.h"
#include "modbus_rtu_driver/simulation/memory_link.h"

using namespace modbus_rtu_driver;

namespace {

constexpr double kGuard = 0.25;  // s

// Every lateness within the guard, 1 ms apart: the simulated line answers at once, so a late
// reply meets the next request's window (between its request and its own reply) for a few ms
// of lateness only; the sweep covers them whatever the frames' times on the wire are.
std::vector<double> latenessesWithinTheGuard() {
  std::vector<double> l;
  for (int ms = 1; ms <= static_cast<int>(kGuard * 1000); ++ms) l.push_back(ms / 1000.0);
  return l;
}

struct Line {
  explicit Line(int retries) : link(config(retries), clock) {
    SimLineSettings line;
    line.baud = 19200;
    link.addDevice(std::make_unique<SimLcRelay8>(1, line));
    link.addDevice(std::make_unique<SimLd58a08>(2, line));
    std::string error;
    EXPECT_TRUE(link.connect(&error)) << error;
    // Channel 1's PWM registers differ from channel 0's (all 0): a read of one that takes the
    // other's reply shows it.
    const Result set = link.execute(Request::writeMultipleRegisters(2, 0x10, {5, 1, 0xFFFF}));
    EXPECT_TRUE(set.ok()) << set.message;
  }
  static LinkConfig config(int retries) {
    LinkConfig c;
    c.port = "memory";
    c.baud = 19200;
    c.response_timeout = 0.2;
    c.retries = retries;
    c.late_reply_guard = kGuard;
    return c;
  }
  Result channel0() { return link.execute(Request::readHoldingRegisters(2, 0x00, 3)); }
  Result channel1() { return link.execute(Request::readHoldingRegisters(2, 0x10, 3)); }

  ManualClock clock;
  MemoryLink link;
};

const std::vector<uint16_t> kChannel0{0, 0, 0};

}  // namespace

// A request that ended early on another device's late reply (a wrong address): its own reply,
// 1 ms after its time-out, is not the next request's. The guard counted from the early end.
TEST(LateReplyGuard, AnAttemptThatEndedEarlyStillWaitsForItsOwnReply) {
  for (const double late_by : latenessesWithinTheGuard()) {
    Line l(0);
    l.link.faults(1).late = 1;
    l.link.faults(1).late_by = 0.05;
    EXPECT_EQ(l.link.execute(Request::readCoils(1, 0, 8)).error, ErrorKind::kTimeout);
    l.link.faults(2).late = 1;
    l.link.faults(2).late_by = late_by;
    const Result early = l.channel1();
    EXPECT_FALSE(early.ok());
    EXPECT_NE(early.error, ErrorKind::kTimeout) << "it read the LC board's late reply";
    const Result next = l.channel0();
    ASSERT_TRUE(next.ok()) << next.message;
    EXPECT_EQ(next.values, kChannel0)
        << "channel 0's read took channel 1's reply, " << late_by << " s late";
  }
}

// A retry that took the first attempt's late reply: its own reply comes as late, after the
// guard the first failure started. The next different request must not take it.
TEST(LateReplyGuard, ARetryAnsweredByTheFirstAttemptsReplyWaitsForItsOwn) {
  for (const double late_by : latenessesWithinTheGuard()) {
    Line l(1);
    l.link.faults(2).late = 2;
    l.link.faults(2).late_by = late_by;
    const Result retried = l.channel1();
    if (!retried.ok()) continue;  // the first reply came after the retry's own window
    const Result next = l.channel0();
    ASSERT_TRUE(next.ok()) << next.message;
    EXPECT_EQ(next.values, kChannel0)
        << "channel 0's read took the retry's reply, " << late_by << " s late";
  }
}

// The wait for one device's guard leaves another device's guard in place: the LD58A08's
// request ended early (on the LC board's late reply) and its own reply is still on its way
// when the LC board's guard has run out.
TEST(LateReplyGuard, OneDevicesQuietLineDoesNotEndAnothersGuard) {
  for (const double late_by : latenessesWithinTheGuard()) {
    Line l(0);
    l.link.faults(1).late = 1;
    l.link.faults(1).late_by = 0.05;
    EXPECT_FALSE(l.link.execute(Request::readCoils(1, 0, 8)).ok());
    l.link.faults(2).late = 1;
    l.link.faults(2).late_by = late_by;
    EXPECT_FALSE(l.channel1().ok());
    // A different request to the LC board: it waits out the board's own guard, which ends
    // before the LD58A08's (the LD58A08's late reply may come in its window: from another
    // address, it is refused, and this read fails).
    l.link.execute(Request::readDiscreteInputs(1, 0, 8));
    const Result next = l.channel0();
    ASSERT_TRUE(next.ok()) << next.message;
    EXPECT_EQ(next.values, kChannel0)
        << "channel 0's read took channel 1's reply, " << late_by << " s late";
  }
}

// A retry of the request that timed out takes its late reply without waiting: it is that
// request's answer.
TEST(LateReplyGuard, ARetryTakesItsRequestsLateReply) {
  Line l(1);
  l.link.faults(2).late = 1;
  l.link.faults(2).late_by = 0.001;
  const Result retried = l.channel1();
  ASSERT_TRUE(retried.ok()) << retried.message;
  EXPECT_EQ(retried.values, (std::vector<uint16_t>{5, 1, 0xFFFF}));
  EXPECT_EQ(l.link.staleRead(), 1u) << "the retry read the first attempt's reply";
}

// A new write with the same frame is no retry: the old echo would confirm a write the device
// may never have heard (a share client's FC05 confirmed by an earlier command's echo, stop 56).
// It waits for the guard like any other request (docs/failsafe.md F90).
TEST(LateReplyGuard, ANewWriteWithTheSameFrameDoesNotTakeTheOldEcho) {
  for (const double late_by : latenessesWithinTheGuard()) {
    Line l(0);
    const Request write = Request::writeMultipleRegisters(2, 0x20, {7, 2, 0xFFFF});
    l.link.faults(2).late = 1;
    l.link.faults(2).late_by = late_by;
    EXPECT_EQ(l.link.execute(write).error, ErrorKind::kTimeout);
    const Result again = l.link.execute(write);
    ASSERT_TRUE(again.ok()) << again.message;
    EXPECT_EQ(l.link.staleRead(), 0u)
        << "the new write took the old one's echo, " << late_by << " s late";
  }
}

// A new read with the failed read's frame may take its late reply, as a retry would (the same
// question, answered a little earlier; F90): it goes without waiting for the guard, so a
// client reading a silent device again and again pays its time-outs only (issue 52). Its own
// reply may then come late in turn: the next different request still waits for it.
TEST(LateReplyGuard, ANewReadWithTheSameFrameGoesWithoutTheGuard) {
  for (const double late_by : latenessesWithinTheGuard()) {
    Line l(0);
    l.link.faults(2).late = 1;
    l.link.faults(2).late_by = late_by;
    EXPECT_EQ(l.channel1().error, ErrorKind::kTimeout);
    const auto before = l.clock.now();
    const Result again = l.channel1();
    const double took = std::chrono::duration<double>(l.clock.now() - before).count();
    ASSERT_TRUE(again.ok()) << again.message;
    EXPECT_EQ(again.values, (std::vector<uint16_t>{5, 1, 0xFFFF}));
    EXPECT_LT(took, kGuard) << "the new read waited for the guard, " << late_by << " s late";
    const Result other = l.channel0();
    ASSERT_TRUE(other.ok()) << other.message;
    EXPECT_EQ(other.values, kChannel0)
        << "a different request took a reply to channel 1's reads, " << late_by << " s late";
  }
}

// The scheduler asks about a new transaction, also right after a retry: a new write with the
// frame of the one whose retry took the first attempt's late echo still waits (its own echo may
// come), and guardLeft says so.
TEST(LateReplyGuard, AfterARetryTheGuardLeftIsANewWritesWait) {
  Line l(1);
  const Request write = Request::writeMultipleRegisters(2, 0x20, {7, 2, 0xFFFF});
  l.link.faults(2).late = 1;
  l.link.faults(2).late_by = 0.001;
  ASSERT_TRUE(l.link.execute(write).ok());
  ASSERT_EQ(l.link.staleRead(), 1u) << "the retry took the first attempt's echo";
  EXPECT_GT(l.link.guardLeft(write), 0.0) << "a new write with its frame would wait";
}

// What the scheduler asks before a request (docs/share.md: shared requests to other devices
// use a guard's time): how long a request to a slave would still wait, which is what the next
// different request to it then waits, and nothing for another slave; and how long a request
// can keep the line, every retry included but not the guard after it.
TEST(LateReplyGuard, TheGuardLeftIsWhatTheNextRequestWaits) {
  Line l(1);
  const Request failed = Request::readHoldingRegisters(2, 0x10, 3);
  const Request next = Request::readHoldingRegisters(2, 0x00, 3);
  EXPECT_EQ(l.link.guardLeft(next), 0.0);
  l.link.faults(2).silent = true;
  const auto sent = l.clock.now();
  EXPECT_EQ(l.channel1().error, ErrorKind::kTimeout);
  const double took = std::chrono::duration<double>(l.clock.now() - sent).count();
  const double line = l.link.lineSeconds(failed);
  EXPECT_LE(took, line) << "the failed read took longer than its longest line time";
  EXPECT_NEAR(line + kGuard, l.link.worstTransactionSeconds(failed), 1e-9);
  const double left = l.link.guardLeft(next);
  EXPECT_GT(left, kGuard * 0.9);
  EXPECT_LE(left, kGuard + 0.2);  // counted from its own reply's time-out, at most 0.2 s on
  EXPECT_EQ(l.link.guardLeft(failed), 0.0) << "a new read with its frame goes at once (F90)";
  EXPECT_EQ(l.link.guardLeft(Request::writeMultipleRegisters(2, 0x10, {5, 1, 0xFFFF})), left)
      << "a write waits, whatever its frame";
  EXPECT_EQ(l.link.guardLeft(Request::readCoils(1, 0, 8)), 0.0) << "the LC board has no guard";
  l.link.faults(2).silent = false;
  const auto before = l.clock.now();
  ASSERT_TRUE(l.channel0().ok());
  const double waited = std::chrono::duration<double>(l.clock.now() - before).count();
  EXPECT_GE(waited, left - 1e-6) << "the next request waited less than guardLeft said";
  EXPECT_EQ(l.link.guardLeft(next), 0.0) << "settled by that wait";
}

// A transaction run in parts (Transport::executeAttempts: a shared read cut short in another
// device's guard, docs/share.md): the part says its retry is owed, the rest is the same
// transaction's retry (no guard of its own, counted as a retry, not a new request), and the link
// never runs more attempts than its retries allow.
TEST(LateReplyGuard, ATransactionCutShortIsContinuedByItsRetry) {
  Line l(1);
  const LinkStats before = l.link.stats();
  l.link.faults(2).lost = 1;
  const Request read = Request::readHoldingRegisters(2, 0x10, 3);
  const Result part = l.link.executeAttempts(read, 0, 1);
  EXPECT_EQ(part.error, ErrorKind::kTimeout);
  EXPECT_TRUE(part.retry_owed);
  EXPECT_EQ(l.link.guardLeft(read), 0.0) << "its retry does not wait for a guard";
  const Result rest = l.link.executeAttempts(read, 1, -1);
  ASSERT_TRUE(rest.ok()) << rest.message;
  EXPECT_FALSE(rest.retry_owed);
  EXPECT_EQ(rest.values, (std::vector<uint16_t>{5, 1, 0xFFFF}));
  const LinkStats after = l.link.stats();
  EXPECT_EQ(after.requests - before.requests, 1u);
  EXPECT_EQ(after.retries - before.retries, 1u);
  EXPECT_EQ(after.attempts - before.attempts, 2u);

  // Lost every time: the retries spent, nothing owed, whatever the caller allows.
  l.link.faults(2).lost = 5;
  EXPECT_TRUE(l.link.executeAttempts(read, 0, 1).retry_owed);
  const Result spent = l.link.executeAttempts(read, 1, 5);
  EXPECT_EQ(spent.error, ErrorKind::kTimeout);
  EXPECT_FALSE(spent.retry_owed);
  EXPECT_EQ(l.link.stats().attempts - after.attempts, 2u) << "1 + retries attempts in all";
}
