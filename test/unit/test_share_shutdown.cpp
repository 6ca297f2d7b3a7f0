// Share requests queued when the node stops never run after the safe states (issue 24, item 5):
// the real BusScheduler, ShareGateway and LcRelay8, a burst of FC05 "relay 0 on" from a client
// while the bus is busy, then the node's shutdown sequence (BusNode::shutdown: share stopped,
// safe writes submitted and waited for, bus stopped). Relay 0 must end in its safe state (off).
#include <gtest/gtest.h>

#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/devices/output_batch.h"
#include "share_test_bus.h"
#include "wait_for.h"

using namespace modbus_rtu_driver;

TEST(ShareShutdown, QueuedClientWritesDoNotRunAfterTheSafeWrites) {
  ShareFixture f;
  ASSERT_TRUE(f.start());
  DeviceConfig dc;
  dc.name = "memory";
  dc.type = "lc_relay8";
  dc.address = 1;
  LcRelay8 board(dc);
  TcpClient client(f.port());
  ASSERT_TRUE(client.connected());
  // The first request holds the bus; the next four wait in the scheduler's shared queue.
  f.bus.hold();
  const Request on = Request::writeSingleCoil(1, 0, true);
  ASSERT_TRUE(client.send(1, on));
  ASSERT_TRUE(f.bus.awaitExecuted(1));
  for (uint16_t t = 2; t <= 5; ++t) ASSERT_TRUE(client.send(t, on));
  ASSERT_TRUE(waitFor([&] { return f.gateway->queued() == 5; }));
  // The node's shutdown sequence.
  f.gateway->stop();
  std::future<Result> safe = f.bus_thread.submit(
      "memory", [&](Transport& t) { return OutputBatch::write(board, t, {0}, {false}); });
  f.bus.release();
  ASSERT_EQ(safe.wait_for(std::chrono::seconds(10)), std::future_status::ready);
  const Result r = safe.get();
  ASSERT_TRUE(r.ok()) << r.message;
  // Every queued client request has its outcome (run or refused) before the bus stops.
  EXPECT_TRUE(waitFor([&] { return f.gateway->queued() == 0; }));
  f.bus_thread.stop();
  EXPECT_EQ(f.bus.coils[0], 0) << "a client's queued write ran after the safe write";
}

TEST(ShareShutdown, ARequestAfterTheShareStoppedIsRefusedUnsent) {
  ShareFixture f;
  ASSERT_TRUE(f.start());
  f.gateway->stop();
  Result got;
  bool called = false;
  bool ran_on_bus = false;
  f.bus_thread.submitShared(
      "memory",
      [&](Transport& t) {
        Result r = t.execute(Request::writeSingleCoil(1, 0, true));
        ran_on_bus = r.ok();
        return r;
      },
      [&](const Result& r) {
        got = r;
        called = true;
      });
  ASSERT_TRUE(called);
  EXPECT_FALSE(ran_on_bus);
  EXPECT_EQ(got.error, ErrorKind::kNotConnected);
  EXPECT_EQ(shareExceptionFor(got), kGatewayPathUnavailable);
  EXPECT_EQ(f.bus.coils[0], 0);
}
