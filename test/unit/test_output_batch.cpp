// Output writes queued for one device merged into one frame: scripted transport, byte exact.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>

#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/devices/output_batch.h"
#include "scripted_transport.h"
#include "wait_for.h"

using namespace modbus_rtu_driver;

namespace {

DeviceConfig relays() {
  DeviceConfig c;
  c.name = "relays";
  c.type = "lc_relay8";
  c.address = 255;
  return c;
}

}  // namespace

TEST(OutputBatch, RequestsQueuedTogetherGoOutAsOneFc15) {
  LcRelay8 board(relays());
  OutputBatch batch;
  auto a = batch.add(board, {0}, {true});
  auto b = batch.add(board, {1}, {true});
  auto c = batch.add(board, {0, 2}, {false, true});  // newer than a for channel 0
  ScriptedTransport bus;
  bus.expectEcho(toHex(encodeRequest(Request::writeMultipleCoils(255, 0, {false, true, true}))));
  const Result ra = batch.complete(board, bus, a);
  EXPECT_TRUE(ra.ok()) << ra.message;
  EXPECT_NE(ra.message.find("merged with 2 other request(s)"), std::string::npos) << ra.message;
  EXPECT_NE(ra.message.find("output 0 superseded"), std::string::npos) << ra.message;
  // b's and c's jobs find their request done: nothing more on the bus.
  const Result rb = batch.complete(board, bus, b);
  const Result rc = batch.complete(board, bus, c);
  EXPECT_TRUE(rb.ok());
  EXPECT_TRUE(rc.ok());
  EXPECT_EQ(rc.message.find("superseded"), std::string::npos) << rc.message;
  EXPECT_EQ(bus.executed(), 1);
  EXPECT_TRUE(bus.usedUp());
  EXPECT_EQ(bus.mismatches(), "");
}

TEST(OutputBatch, AFailedWriteFailsEveryMergedRequest) {
  LcRelay8 board(relays());
  OutputBatch batch;
  auto a = batch.add(board, {3}, {true});
  auto b = batch.add(board, {4}, {true});
  ScriptedTransport bus;
  bus.expect(toHex(encodeRequest(Request::writeMultipleCoils(255, 3, {true, true}))),
             toHex(encodeException(255, 0x0F, 4)));
  EXPECT_EQ(batch.complete(board, bus, a).error, ErrorKind::kException);
  EXPECT_EQ(batch.complete(board, bus, b).error, ErrorKind::kException);
  EXPECT_TRUE(bus.usedUp());
}

// docs/failsafe.md, "A command whose answer was lost": every channel a merged write carried is
// unknown until the next poll, not only the channels of the request whose job sent it (seed
// 12016 of the fail-safe simulation: a set merged into a command's write was left as before).
TEST(OutputBatch, AWriteNotConfirmedNamesEveryMergedChannelOnce) {
  LcRelay8 board(relays());
  OutputBatch batch;
  auto command = batch.add(board, {1}, {true});
  auto set = batch.add(board, {0}, {true});
  ScriptedTransport bus;
  bus.expect(toHex(encodeRequest(Request::writeMultipleCoils(255, 0, {true, true}))));
  bus.expect(toHex(encodeRequest(Request::readCoils(255, 0, 8))));  // the read back: no reply too
  int calls = 0;
  std::vector<uint8_t> unknown;
  const auto not_confirmed = [&](const std::vector<uint8_t>& chs, const Result& r,
                                 const std::vector<uint8_t>& changed) {
    ++calls;
    unknown = chs;
    EXPECT_EQ(r.error, ErrorKind::kTimeout);
    EXPECT_TRUE(changed.empty()) << "one frame, not confirmed: nothing changed for sure";
  };
  EXPECT_FALSE(batch.complete(board, bus, command, {}, not_confirmed).ok());
  EXPECT_FALSE(batch.complete(board, bus, set, {}, not_confirmed).ok());
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(unknown, (std::vector<uint8_t>{0, 1}));
  EXPECT_TRUE(bus.usedUp());
  EXPECT_EQ(bus.mismatches(), "");
}

TEST(OutputBatch, ALoneRequestIsOneFc05) {
  LcRelay8 board(relays());
  OutputBatch batch;
  auto a = batch.add(board, {5}, {true});
  ScriptedTransport bus;
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleCoil(255, 5, true))));
  const Result r = batch.complete(board, bus, a);
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.message, "");
  EXPECT_TRUE(bus.usedUp());
}

// A request is checked once, as it is added: a bad one is refused there, with the device's
// text, and never joins the merged write (which is not checked again).
TEST(OutputBatch, ABadRequestIsRefusedAsItIsAdded) {
  LcRelay8 board(relays());
  OutputBatch batch;
  // `if (!...) FAIL()`, not ASSERT_TRUE: clang-tidy 19 sees that FAIL() returns, not ASSERT_TRUE.
  auto bad = batch.add(board, {9}, {true});
  const std::optional<Result>& bad_result = bad->result;
  if (!bad_result) FAIL() << "channel 9 was not refused";
  EXPECT_EQ(bad_result->error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(bad_result->message, "channel: 9 is outside 0-7");
  auto twice = batch.add(board, {2, 2}, {true, false});
  const std::optional<Result>& twice_result = twice->result;
  if (!twice_result) FAIL() << "channel 2 given twice was not refused";
  EXPECT_EQ(twice_result->message, "channel: 2 is given twice");
  auto good = batch.add(board, {1}, {true});
  EXPECT_FALSE(good->result.has_value());
  ScriptedTransport bus;
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleCoil(255, 1, true))));
  const Result r = batch.complete(board, bus, good);
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.message, "");  // alone: the refused ones were never merged
  EXPECT_TRUE(bus.usedUp());
  EXPECT_EQ(bus.mismatches(), "");
}

namespace {

// The scripted device behind a port that can be taken away and given back.
class UnpluggableTransport : public ScriptedTransport {
 public:
  bool connect(std::string* error) override {
    open_ = plugged_.load();
    if (!open_ && error) *error = "no such device";
    return open_;
  }
  bool connected() const override { return open_; }
  void disconnect() override { open_ = false; }
  std::atomic<bool> plugged_{false};

 private:
  std::atomic<bool> open_{false};
};

}  // namespace

// A write refused while the port was gone must never go out later, merged into another one
// (review defect: relay 3 switched on after its caller was told it failed).
TEST(OutputBatch, ARequestRefusedWhileThePortIsGoneIsNeverSentLater) {
  auto board = std::make_shared<LcRelay8>(relays());
  OutputBatch batch;
  UnpluggableTransport port;
  BusScheduler::Options o;
  o.reconnect_initial = 0.01;
  o.reconnect_max = 0.01;
  BusScheduler scheduler(port, o);
  scheduler.addDevice("relays");
  scheduler.start();
  auto job = [&](const std::shared_ptr<OutputBatch::Entry>& e) {
    return [&, e](Transport& t) { return batch.complete(*board, t, e); };
  };
  const Result refused = scheduler.submit("relays", job(batch.add(*board, {3}, {true}))).get();
  EXPECT_EQ(refused.error, ErrorKind::kNotConnected) << refused.message;

  port.expectEcho(toHex(encodeRequest(Request::writeSingleCoil(255, 7, true))));
  port.plugged_ = true;
  ASSERT_TRUE(waitFor([&] { return scheduler.connected(); }, 10.0));
  const Result later = scheduler.submit("relays", job(batch.add(*board, {7}, {true}))).get();
  EXPECT_TRUE(later.ok()) << later.message;
  EXPECT_EQ(later.message, "");  // not "merged with 1 other request(s)"
  scheduler.stop();
  EXPECT_TRUE(port.usedUp());
  EXPECT_EQ(port.mismatches(), "");  // only channel 7 went out: FC05, not FC15 over 3-7
}
