// Output writes touch only the channels asked for (issue 24, item 4): FC05 for a lone channel,
// FC15 per run of adjacent channels, never a frame over a channel between two requested ones
// (on the LC board that rewrite cancels a running flash, on the LD58A08 it fights a running
// PWM). Checked byte for byte against a scripted transport.
#include <gtest/gtest.h>

#include "device_fixtures.h"
#include "modbus_rtu_driver/devices/failsafe.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/devices/ld58a08.h"
#include "modbus_rtu_driver/devices/output_batch.h"
#include "modbus_rtu_driver/devices/yespeed_pdu.h"

using namespace modbus_rtu_driver;
using namespace modbus_rtu_driver::devtest;

namespace {

std::string hexOf(const Request& r) {
  return toHex(encodeRequest(r));
}

// `request` answered as the device would (a copy for FC05, the 8-byte answer for FC15).
void expectAnswered(ScriptedTransport& bus, const Request& request) {
  bus.expect(hexOf(request), toHex(encodeReply(request, {})));
}

void expectPwm(ScriptedTransport& bus, uint8_t ch, uint16_t enable) {
  const Request read = Request::readHoldingRegisters(1, static_cast<uint16_t>(ch * 0x10), 3);
  bus.expect(hexOf(read), toHex(encodeReply(read, {10, 5, enable})));
}

}  // namespace

TEST(CoilRuns, AdjacentChannelsMakeOneRunInChannelOrder) {
  const auto runs = coilRuns({5, 0, 2, 1, 7, 6}, {true, false, true, true, false, true});
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0].first, 0);
  EXPECT_EQ(runs[0].states, (std::vector<bool>{false, true, true}));
  EXPECT_EQ(runs[1].first, 5);
  EXPECT_EQ(runs[1].states, (std::vector<bool>{true, true, false}));
}

TEST(LcRelay8Writes, TwoChannelsWithAGapAreTwoFc05AndTheGapIsNotWritten) {
  LcRelay8 board(config("lc_relay8", 255));
  ScriptedTransport bus;
  // The manual's FC05 frames at the factory address: relay #1 and relay #3, nothing else (no
  // read of the coils, no FC15 over relay #2).
  bus.expect("FF 05 00 00 FF 00 99 E4", "FF 05 00 00 FF 00 99 E4");
  bus.expect("FF 05 00 02 FF 00 38 24", "FF 05 00 02 FF 00 38 24");
  const Result r = OutputBatch::write(board, bus, {0, 2}, {true, true});
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_SCRIPT_DONE(bus);
}

TEST(LcRelay8Writes, RunsOfAdjacentChannelsAreOneFc15Each) {
  LcRelay8 board(config("lc_relay8", 3));
  ScriptedTransport bus;
  expectAnswered(bus, Request::writeMultipleCoils(3, 0, {true, false}));
  expectAnswered(bus, Request::writeMultipleCoils(3, 4, {true, true, false}));
  const Result r =
      OutputBatch::write(board, bus, {6, 0, 4, 1, 5}, {false, true, true, false, true});
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_SCRIPT_DONE(bus);
}

TEST(LcRelay8Writes, TheSnapshotTakesOnlyTheWrittenChannels) {
  LcRelay8 board(config("lc_relay8", 3));
  ScriptedTransport bus;
  const Request poll = Request::readCoils(3, 0, 8);
  bus.expect(hexOf(poll), toHex(encodeReply(poll, {0, 1, 0, 1, 0, 0, 0, 0})));
  const Request inputs = Request::readDiscreteInputs(3, 0, 8);
  bus.expect(hexOf(inputs), toHex(encodeReply(inputs, {0, 0, 0, 0, 0, 0, 0, 0})));
  ASSERT_TRUE(board.poll(bus).ok());
  expectAnswered(bus, Request::writeSingleCoil(3, 0, true));
  expectAnswered(bus, Request::writeSingleCoil(3, 2, true));
  ASSERT_TRUE(OutputBatch::write(board, bus, {0, 2}, {true, true}).ok());
  EXPECT_EQ(board.outputs(), (std::vector<bool>{1, 1, 1, 1, 0, 0, 0, 0}));
  EXPECT_SCRIPT_DONE(bus);
}

TEST(LcRelay8Writes, AFailedRunStopsTheWriteAndSaysWhatWasWritten) {
  LcRelay8 board(config("lc_relay8", 3));
  ScriptedTransport bus;
  expectAnswered(bus, Request::writeSingleCoil(3, 0, true));
  const Request second = Request::writeSingleCoil(3, 2, true);
  bus.expect(hexOf(second), toHex(encodeException(3, 0x05, kSlaveDeviceFailure)));
  const Result r = OutputBatch::write(board, bus, {0, 2, 5}, {true, true, true});
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.message.find("outputs 0 were written before, the others not"), std::string::npos)
      << r.message;
  EXPECT_SCRIPT_DONE(bus);  // no frame for channel 5 after the failure
}

TEST(LcRelay8Writes, ASafeStateMapWithHoldBetweenWritesOnlyTheSafeChannels) {
  FailsafeConfig fs;
  fs.safe_state = {SafeState::kOff, SafeState::kLeave, SafeState::kOff,   SafeState::kLeave,
                   SafeState::kOn,  SafeState::kOn,    SafeState::kLeave, SafeState::kLeave};
  const OutputTargets safe = fs.safeTargets(LcRelay8::kChannels);
  LcRelay8 board(config("lc_relay8", 3));
  ScriptedTransport bus;
  expectAnswered(bus, Request::writeSingleCoil(3, 0, false));
  expectAnswered(bus, Request::writeSingleCoil(3, 2, false));
  expectAnswered(bus, Request::writeMultipleCoils(3, 4, {true, true}));
  const Result r = OutputBatch::write(board, bus, safe.channels, safe.states);
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_SCRIPT_DONE(bus);  // relays 1, 3, 6, 7 (hold) never on the wire
}

TEST(LcRelay8Writes, MergedRequestsWithAGapStayTwoWrites) {
  LcRelay8 board(config("lc_relay8", 3));
  OutputBatch batch;
  auto a = batch.add(board, {0}, {true});
  auto b = batch.add(board, {2}, {false});
  ScriptedTransport bus;
  expectAnswered(bus, Request::writeSingleCoil(3, 0, true));
  expectAnswered(bus, Request::writeSingleCoil(3, 2, false));
  EXPECT_TRUE(batch.complete(board, bus, a).ok());
  EXPECT_TRUE(batch.complete(board, bus, b).ok());
  EXPECT_SCRIPT_DONE(bus);
}

TEST(Ld58a08Writes, AnOutputUnderARunningPwmBetweenTwoRequestedIsNotRewritten) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  // Channel 1 runs a PWM and is not asked for: only channels 0 and 2 are read and written.
  expectPwm(bus, 0, 0);
  expectPwm(bus, 2, 0);
  bus.expect("01 05 00 00 FF 00 8C 3A", "01 05 00 00 FF 00 8C 3A");
  bus.expect("01 05 00 02 00 00 6C 0A", "01 05 00 02 00 00 6C 0A");
  const Result r = OutputBatch::write(board, bus, {0, 2}, {true, false});
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_SCRIPT_DONE(bus);
}

TEST(Ld58a08Writes, RunsOfAdjacentOutputsAreOneFc15Each) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  for (uint8_t ch : {0, 1, 5, 6}) expectPwm(bus, ch, 0);
  expectAnswered(bus, Request::writeMultipleCoils(1, 0, {true, true}));
  expectAnswered(bus, Request::writeMultipleCoils(1, 5, {false, true}));
  const Result r = OutputBatch::write(board, bus, {0, 1, 5, 6}, {true, true, false, true});
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_SCRIPT_DONE(bus);
}

TEST(YespeedPduWrites, RelaysWithAGapAreWrittenAloneAndTheGapIsNotWritten) {
  YespeedPdu pdu(config("yespeed_pdu", 1));
  ScriptedTransport bus;
  expectAnswered(bus, Request::writeSingleCoil(1, 1, true));
  expectAnswered(bus, Request::writeMultipleCoils(1, 3, {false, false}));
  expectAnswered(bus, Request::writeSingleCoil(1, 7, true));
  const Result r = OutputBatch::write(pdu, bus, {1, 3, 4, 7}, {true, false, false, true});
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_SCRIPT_DONE(bus);
}

TEST(YespeedPduWrites, ALostReplyIsConfirmedPerRun) {
  YespeedPdu pdu(config("yespeed_pdu", 1));
  ScriptedTransport bus;
  bus.expect(hexOf(Request::writeSingleCoil(1, 1, true)));  // reply lost
  const Request back = Request::readCoils(1, 0, 8);
  bus.expect(hexOf(back), toHex(encodeReply(back, {0, 1, 0, 0, 0, 0, 0, 0})));
  expectAnswered(bus, Request::writeSingleCoil(1, 6, true));
  const Result r = OutputBatch::write(pdu, bus, {1, 6}, {true, true});
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_NE(r.message.find("confirmed by reading the outputs back"), std::string::npos)
      << r.message;
  EXPECT_EQ(pdu.outputs(), (std::vector<bool>{0, 1, 0, 0, 0, 0, 1, 0}));
  EXPECT_SCRIPT_DONE(bus);
}
