// The simulator's injected faults over a real pty, one at a time: what the wire carries, and the
// counters a test reads back (changes, dropped requests and replies).
#include <gtest/gtest.h>

#include "test_sim_helpers.h"

using namespace modbus_rtu_driver;
using namespace modbus_rtu_driver::simtest;

namespace {

const Request kRead = Request::readCoils(2, 0, 8);

std::string good() {
  return toHex(encodeReply(kRead, std::vector<uint16_t>(8)));
}

}  // namespace

TEST(SimFaults, SilenceFailAndCorrupt) {
  Line line({{"yespeed_pdu", 2}});
  PtyClient client(line.link());
  const Bytes read = encodeRequest(kRead);
  ASSERT_EQ(line("silence 2 1"), "ok");
  EXPECT_EQ(client.exchange(read), "");
  ASSERT_TRUE(line.tookFrames(1));  // heard while silenced, not answered after "silence 2 0"
  ASSERT_EQ(line("silence 2 0"), "ok");
  EXPECT_EQ(client.exchange(read, 6), good());
  ASSERT_EQ(line("fail 2 1"), "ok");
  EXPECT_EQ(client.exchange(read, 5), exceptionHex(2, 0x01, kSlaveDeviceFailure));
  ASSERT_EQ(line("fail 2 0"), "ok");
  ASSERT_EQ(line("corrupt 2 2"), "ok");
  for (int i = 0; i < 2; ++i) {
    const auto reply = fromHex(client.exchange(read, 6));
    ASSERT_TRUE(reply && reply->size() == 6);
    EXPECT_FALSE(hasValidCrc(*reply));
  }
  EXPECT_EQ(client.exchange(read, 6), good());
}

TEST(SimFaults, TruncatedWrongAddressAndNoise) {
  Line line({{"yespeed_pdu", 2}});
  PtyClient client(line.link());
  const Bytes read = encodeRequest(kRead);
  ASSERT_EQ(line("truncate 2 1"), "ok");
  EXPECT_EQ(client.exchange(read), good().substr(0, 8)) << "half of the 6 bytes";
  ASSERT_EQ(line("wrong_address 2 1"), "ok");
  const auto other = fromHex(client.exchange(read, 6));
  ASSERT_TRUE(other && other->size() == 6);
  EXPECT_EQ((*other)[0], 1) << "another slave's address";
  EXPECT_TRUE(hasValidCrc(*other)) << "a valid frame, only from the wrong slave";
  ASSERT_EQ(line("noise 2 1"), "ok");
  EXPECT_EQ(client.exchange(read), good() + " 00 FF 55 03 13");
  EXPECT_EQ(client.exchange(read), good()) << "one reply only";
}

TEST(SimFaults, LateRepliesComeAfterTheirDelay) {
  Line line({{"yespeed_pdu", 2}});
  PtyClient client(line.link());
  ASSERT_EQ(line("late 2 1 400"), "ok");
  client.receive(256, 0ms);
  client.send(encodeRequest(kRead));
  EXPECT_EQ(toHex(client.receive(6, 250ms)), "") << "nothing within 250 ms";
  EXPECT_EQ(toHex(client.receive(6, 1000ms)), good()) << "then the reply";
  EXPECT_EQ(client.exchange(encodeRequest(kRead), 6, 100ms), good()) << "the next one at once";
}

TEST(SimFaults, DroppedRequestsDoNothingDroppedRepliesStillAct) {
  Line line({{"yespeed_pdu", 2}});
  PtyClient client(line.link());
  ASSERT_EQ(line("drop 2 100 request"), "ok");
  const Bytes on = encodeRequest(Request::writeSingleCoil(2, 0, true));
  EXPECT_EQ(client.exchange(on, 8, 100ms), "");
  // 100 ms of silence does not mean the simulator has read the request: wait until it has
  // (else the drop setting could change under it, and the state be read before it acted).
  ASSERT_TRUE(line.tookFrames(1));
  EXPECT_EQ(line("get 2 coil 0"), "ok 0") << "never heard";
  ASSERT_EQ(line("drop 2 0 request"), "ok");
  ASSERT_EQ(line("drop 2 100 reply"), "ok");
  EXPECT_EQ(client.exchange(on, 8, 100ms), "");
  ASSERT_TRUE(line.tookFrames(2));
  EXPECT_EQ(line("get 2 coil 0"), "ok 1") << "done, only the reply lost";
  EXPECT_EQ(line("stats 2"), "ok changes 1 dropped_requests 1 dropped_replies 1");
  ASSERT_EQ(line("drop 2 0 reply"), "ok");
  EXPECT_EQ(client.exchange(on, 8), toHex(on)) << "the echo again";
  EXPECT_EQ(line("stats 2"), "ok changes 1 dropped_requests 1 dropped_replies 1")
      << "the same value again is no change";
}

TEST(SimFaults, ADropShareIsRoughlyKept) {
  Line line({{"yespeed_pdu", 2}});
  PtyClient client(line.link());
  ASSERT_EQ(line("drop 2 20 reply"), "ok");
  // The simulator's replies so far: written whole, and dropped.
  auto replies = [&] {
    unsigned long long received = 0, answered = 0, dropped = 0, dropped_replies = 0;
    std::sscanf(line("frames").c_str(), "ok %llu %llu %llu", &received, &answered, &dropped);
    std::sscanf(line("stats 2").c_str(), "ok changes %*u dropped_requests %*u dropped_replies %llu",
                &dropped_replies);
    return std::make_pair(answered, dropped_replies);
  };
  int lost = 0;
  unsigned long long dropped_before = 0;
  for (int i = 0; i < 200; ++i) {
    if (!client.exchange(encodeRequest(kRead), 6, 150ms).empty()) continue;
    // Silence for 150 ms: a lost reply, or a late one on a loaded machine. Once the simulator is
    // done with the request, a reply it says it wrote must arrive; one it dropped stays lost.
    std::pair<unsigned long long, unsigned long long> done;
    ASSERT_TRUE(waitFor([&] {
      done = replies();
      return done.first + done.second >= static_cast<unsigned long long>(i) + 1;
    }));
    const bool dropped = done.second > dropped_before;
    dropped_before = done.second;
    lost += dropped || client.receive(6, 2000ms).empty();
  }
  EXPECT_GT(lost, 15);
  EXPECT_LT(lost, 70);
  EXPECT_EQ(line("stats 2"),
            "ok changes 0 dropped_requests 0 dropped_replies " + std::to_string(lost));
}

TEST(SimFaults, RestartingWritesCountAsChangesEachTime) {
  Line line({{"ld58a08", 1}, {"lc_relay8", 255}});
  PtyClient client(line.link());
  const Bytes burst = encodeRequest(Request::writeMultipleRegisters(1, 0x0000, {10, 5, 3}));
  const Bytes flash = encodeRequest(Request::writeMultipleRegisters(255, 0x0003, {4, 20}));
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(client.exchange(burst, 8).size(), 8 * 3 - 1u);
    EXPECT_EQ(client.exchange(flash, 8).size(), 8 * 3 - 1u);
  }
  EXPECT_EQ(line("stats 1"), "ok changes 2 dropped_requests 0 dropped_replies 0");
  EXPECT_EQ(line("stats 255"), "ok changes 2 dropped_requests 0 dropped_replies 0");
}

TEST(SimFaults, BadFaultArgumentsAreNamed) {
  Line line({{"yespeed_pdu", 2}});
  EXPECT_EQ(line("drop 2 101 reply"), "error drop: '101' is not a percentage 0-100");
  EXPECT_EQ(line("drop 2 5 both"), "error drop: say request or reply, not 'both'");
  EXPECT_EQ(line("late 2 1 x"), "error late: 'x' is not 0-60000 milliseconds");
  EXPECT_EQ(line("truncate 2 -1"), "error truncate: '-1' is not a count");
  EXPECT_EQ(line("stats 9").substr(0, 15), "error no device");
}
