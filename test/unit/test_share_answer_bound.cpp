// The share's answer bound (docs/share.md, "How long an answer takes"): a request that cannot
// start in time is answered 0B at its latest start, by the gateway's own thread while the bus is
// busy, and is never sent; the bound is twice the longest transaction unless answer_within sets
// it, and an answer_within shorter than that transaction stops the start, naming both. The real
// ShareGateway and BusScheduler over a MemoryBus whose transaction the test holds; the bound's
// time is a ManualClock, so nothing here waits for real time to pass.
#include <gtest/gtest.h>

#include "share_test_bus.h"
#include "wait_for.h"

using namespace modbus_rtu_driver;

namespace {

// Every transaction takes at most 0.1 s here, a broadcast 0.05 s (before its turnaround).
double tenthOfASecond(const Request& r) {
  return r.slave == kBroadcastAddress ? 0.05 : 0.1;
}

ShareConfig shareConfig(double answer_within = 0.0) {
  ShareConfig c;
  c.answer_within = answer_within;
  c.broadcast_turnaround = 0.1;
  return c;
}

Clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

TEST(ShareAnswerBound, ARequestThatCannotStartInTimeIsAnswered0BAndNeverSent) {
  ManualClock clock;
  ShareFixture f(shareConfig(), tenthOfASecond, clock);
  ASSERT_TRUE(f.start());
  EXPECT_DOUBLE_EQ(f.gateway->longestTransaction(), 0.15);  // a broadcast and its turnaround
  EXPECT_DOUBLE_EQ(f.gateway->answerBound(), 0.3);
  TcpClient client(f.port());
  ASSERT_TRUE(client.connected());
  // The first request holds the bus (a silent device's retries, say); the second waits.
  f.bus.hold();
  const Request read = Request::readHoldingRegisters(1, 0, 2);
  ASSERT_TRUE(client.send(1, read));
  ASSERT_TRUE(f.bus.awaitExecuted(1));
  ASSERT_TRUE(client.send(2, read));
  ASSERT_TRUE(waitFor([&] { return f.gateway->queued() == 2; }));
  // Its latest start: 0.3 - 0.1 s after it came. Before it, nothing is answered.
  clock.advance(seconds(0.19));
  EXPECT_TRUE(client.receive(0.2).empty()) << "answered before its latest start";
  clock.advance(seconds(0.02));
  const Bytes answer = client.receive();
  ASSERT_EQ(answer.size(), 9u) << toHex(answer);
  EXPECT_EQ(mbapTransaction(answer), 2);
  EXPECT_EQ(TcpClient::asRtu(answer),
            encodeException(1, static_cast<uint8_t>(FunctionCode::kReadHoldingRegisters),
                            kGatewayTargetFailed));
  EXPECT_EQ(f.gateway->expired(), 1u);
  // The held transaction ends: its own answer, and the expired request is passed unsent.
  f.bus.release();
  const Bytes first = client.receive();
  ASSERT_GE(first.size(), 8u);
  EXPECT_EQ(mbapTransaction(first), 1);
  EXPECT_EQ(TcpClient::asRtu(first), encodeReply(read, {0, 0}));
  ASSERT_TRUE(waitFor([&] { return f.gateway->queued() == 0; }));
  EXPECT_EQ(f.bus.executed(), 1) << "the expired request reached the bus";
  // The next request, in time, runs as usual.
  ASSERT_TRUE(client.send(3, read));
  const Bytes third = client.receive();
  ASSERT_GE(third.size(), 8u);
  EXPECT_EQ(mbapTransaction(third), 3);
  EXPECT_EQ(TcpClient::asRtu(third), encodeReply(read, {0, 0}));
  EXPECT_EQ(f.bus.executed(), 2);
  EXPECT_EQ(f.gateway->expired(), 1u);
}

TEST(ShareAnswerBound, AnswerWithinSetsTheBound) {
  ManualClock clock;
  ShareFixture f(shareConfig(0.9), tenthOfASecond, clock);
  ASSERT_TRUE(f.start());
  EXPECT_DOUBLE_EQ(f.gateway->answerBound(), 0.9);
  TcpClient client(f.port());
  ASSERT_TRUE(client.connected());
  f.bus.hold();
  const Request write = Request::writeSingleCoil(1, 3, true);
  ASSERT_TRUE(client.send(1, write));
  ASSERT_TRUE(f.bus.awaitExecuted(1));
  ASSERT_TRUE(client.send(2, write));
  ASSERT_TRUE(waitFor([&] { return f.gateway->queued() == 2; }));
  clock.advance(seconds(0.75));  // before 0.9 - 0.1
  EXPECT_TRUE(client.receive(0.2).empty());
  clock.advance(seconds(0.1));
  const Bytes answer = client.receive();
  ASSERT_EQ(answer.size(), 9u);
  EXPECT_EQ(mbapTransaction(answer), 2);
  EXPECT_EQ(answer[7], 0x85);
  EXPECT_EQ(answer[8], kGatewayTargetFailed);
  f.bus.release();
  ASSERT_TRUE(waitFor([&] { return f.gateway->queued() == 0; }));
  EXPECT_EQ(f.bus.executed(), 1) << "a write the client was told failed was sent later";
}

TEST(ShareAnswerBound, AnAnswerWithinShorterThanTheLongestTransactionStopsTheStart) {
  ManualClock clock;
  ShareFixture f(shareConfig(0.12), tenthOfASecond, clock);
  f.bus_thread.start();
  std::string error;
  EXPECT_FALSE(f.gateway->start(&error));
  EXPECT_NE(error.find("answer_within: 0.12"), std::string::npos) << error;
  EXPECT_NE(error.find("(0.15"), std::string::npos) << error;
}

TEST(ShareAnswerBound, WithoutATransactionTimeThereIsNoBound) {
  ShareFixture f;
  ASSERT_TRUE(f.start());
  EXPECT_EQ(f.gateway->answerBound(), 0.0);
}

// docs/share.md: a read run in another device's late-reply guard gets the attempts that end
// before the guard does; its answer lost in them, its remaining retries go after the guarded
// request, and the client gets their answer, or 0B by the answer bound when they cannot start
// in time (then they are never sent).
namespace {

// Read #1 holds the bus while a ROS write to the guarded slave 3 and read #2 queue behind it;
// released, the write's guard lets read #2's first attempt go (one 0.04 s attempt fits the
// 0.05 s left), and its answer is lost.
struct CutShortRead {
  explicit CutShortRead(ManualClock& clock) : f(shareConfig(), tenthOfASecond, clock) {
    f.bus.guarded = 3;
    f.bus.guard_left = 0.05;
    f.bus.owed = 1;
  }
  // Returns read #2's answer.
  Bytes run() {
    if (!f.start()) return {};
    client = std::make_unique<TcpClient>(f.port());
    f.bus.hold();
    if (!client->send(1, read) || !f.bus.awaitExecuted(1)) return {};
    write = f.bus_thread.submit(
        "board", [](Transport& t) { return t.execute(Request::writeSingleCoil(3, 0, true)); });
    if (!client->send(2, read) || !waitFor([&] { return f.gateway->queued() == 2; })) return {};
    f.bus.release();
    Bytes answer;
    for (int i = 0; i < 2; ++i) {  // read #1's answer and read #2's, in either order
      const Bytes frame = client->receive();
      if (frame.size() >= 8 && mbapTransaction(frame) == 2) answer = frame;
    }
    return answer;
  }
  ShareFixture f;
  std::unique_ptr<TcpClient> client;
  const Request read = Request::readHoldingRegisters(1, 0, 2);
  std::future<Result> write;
};

}  // namespace

TEST(ShareAnswerBound, AReadCutShortInAGuardIsAnsweredAfterItsRetry) {
  ManualClock clock;
  CutShortRead c(clock);
  c.f.bus.on_owed = [&c] { c.f.bus.guard_left = 0.03; };  // the retry does not fit what is left
  const Bytes answer = c.run();
  EXPECT_EQ(TcpClient::asRtu(answer), encodeReply(c.read, {0, 0})) << toHex(answer);
  c.write.wait();  // sent (the order below); MemoryBus answers slave 1 only
  EXPECT_EQ(c.f.bus.order(), (std::vector<uint8_t>{1, 1, 3, 1}))
      << "read #1, read #2's first attempt in the guard, the guarded write, read #2's retry";
  EXPECT_EQ(c.f.gateway->expired(), 0u);
}

TEST(ShareAnswerBound, AReadCutShortWhoseRetryCannotStartInTimeIsAnswered0BAndItsRetryNeverSent) {
  ManualClock clock;
  CutShortRead c(clock);
  c.f.bus.on_owed = [&c, &clock] {
    c.f.bus.guard_left = 0.03;
    clock.advance(seconds(0.25));  // past read #2's latest start (0.3 - 0.1 s after it came)
  };
  const Bytes answer = c.run();
  EXPECT_EQ(TcpClient::asRtu(answer),
            encodeException(1, static_cast<uint8_t>(FunctionCode::kReadHoldingRegisters),
                            kGatewayTargetFailed))
      << toHex(answer);
  c.write.wait();  // sent (the order below); MemoryBus answers slave 1 only
  ASSERT_TRUE(waitFor([&] { return c.f.gateway->queued() == 0; }));
  EXPECT_EQ(c.f.bus.order(), (std::vector<uint8_t>{1, 1, 3})) << "the retry was sent";
  EXPECT_EQ(c.f.gateway->expired(), 1u);
}
