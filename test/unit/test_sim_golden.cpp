// Every frame the manuals print, through the simulated devices: each printed reply byte for
// byte, each request without a printed reply accepted (not an exception).
#include <gtest/gtest.h>

#include <map>

#include "golden_frames.h"
#include "modbus_rtu_driver/sim/simulator.h"
#include "test_sim_helpers.h"

using namespace modbus_rtu_driver;
using namespace modbus_rtu_driver::simtest;

namespace {

bool simulated(const GoldenFrame& g) {
  return g.device == "ld58a08" || g.device == "lc_relay8" || g.device == "yespeed_pdu";
}

// A device at its factory address, in the state a printed read reply shows.
std::unique_ptr<SimDevice> deviceFor(const GoldenFrame& g, const Request& r) {
  auto d = makeSimDevice({g.device, g.device == "lc_relay8" ? 255 : 1}, SimLineSettings{});
  const auto now = SimClock::now();
  const Bytes& reply = g.response;
  if (reply.empty() || !isReadFunction(r.function)) return d;
  const Table t = r.function == FunctionCode::kReadCoils            ? Table::kCoil
                  : r.function == FunctionCode::kReadDiscreteInputs ? Table::kDiscreteInput
                  : r.function == FunctionCode::kReadInputRegisters ? Table::kInputRegister
                                                                    : Table::kHoldingRegister;
  for (uint16_t i = 0; i < r.count; ++i) {
    const uint16_t a = static_cast<uint16_t>(r.address + i);
    const uint16_t v = isBitFunction(r.function)
                           ? (reply[3 + i / 8] >> (i % 8)) & 1
                           : static_cast<uint16_t>(reply[3 + 2 * i] << 8 | reply[4 + 2 * i]);
    if (t != Table::kHoldingRegister) {
      EXPECT_EQ(d->setDirect(t, a, v, now), 0) << g.meaning;
    } else if (a == 0x0080) {
      EXPECT_EQ(d->write(t, a, {v}, now), 0) << g.meaning;  // outputs as the reply shows
    } else if (a == 0x03E8) {
      EXPECT_EQ(d->write(t, 0x03E9, {v}, now), 0) << g.meaning;  // the stored baud code
    }
  }
  return d;
}

}  // namespace

TEST(SimGolden, EveryPrintedReplyByteForByte) {
  std::map<std::string, int> compared;
  for (const auto& g : loadGoldenFrames(GOLDEN_FRAMES_PATH)) {
    if (!simulated(g) || g.response.empty()) continue;
    const auto request = decodeRequest(g.request);
    ASSERT_TRUE(request.has_value()) << g.meaning;
    auto device = deviceFor(g, *request);
    EXPECT_EQ(ask(*device, toHex(g.request)), toHex(g.response)) << g.device << ": " << g.meaning;
    ++compared[g.device];
  }
  // The manuals print 17 LD58A08 replies, 12 LC board replies, 8 PDU replies.
  EXPECT_EQ(compared["ld58a08"], 17);
  EXPECT_EQ(compared["lc_relay8"], 12);
  EXPECT_EQ(compared["yespeed_pdu"], 8);
}

TEST(SimGolden, EveryRequestWithoutAPrintedReplyIsAccepted) {
  // In the manual's order, on one device per type (the PWM examples write the period first).
  std::map<std::string, std::unique_ptr<SimDevice>> devices;
  int accepted = 0;
  for (const auto& g : loadGoldenFrames(GOLDEN_FRAMES_PATH)) {
    if (!simulated(g) || !g.response.empty()) continue;
    auto& device = devices[g.device];
    if (!device) device = makeSimDevice({g.device, g.device == "lc_relay8" ? 255 : 1}, {});
    const std::string reply = ask(*device, toHex(g.request));
    ASSERT_GE(reply.size(), 8u) << g.meaning;
    EXPECT_EQ(fromHex(reply)->at(1), g.request[1]) << "not an exception: " << g.meaning;
    ++accepted;
  }
  EXPECT_EQ(accepted, 20);
}

TEST(SimGolden, RepliesFollowFromStateNotFromTheTable) {
  // The same read in another state gives another (CRC-correct) reply.
  auto ld = makeSimDevice({"ld58a08", 1}, {});
  EXPECT_EQ(ask(*ld, "01 01 00 00 00 08 3D CC"),
            toHex(encodeReply(Request::readCoils(1, 0, 8), {0, 0, 0, 0, 0, 0, 0, 0})));
  EXPECT_EQ(ask(*ld, "01 0F 00 00 00 08 01 89 3F 33"), "01 0F 00 00 00 08 54 0D");
  EXPECT_EQ(ask(*ld, "01 03 00 80 00 01 85 E2"),
            toHex(encodeReply(Request::readHoldingRegisters(1, 0x80, 1), {0x89})));
}
