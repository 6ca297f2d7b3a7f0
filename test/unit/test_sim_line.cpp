// The simulated line over a real pty, in-process: the manuals' frames byte for byte, silence for
// bad CRCs and unknown addresses, resynchronisation after noise, broadcasts, the line's settings,
// the return delay, an LD58A08 at 0xFF colliding with an LC board at 255, fault injection and
// pacing.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <memory>

#include "golden_frames.h"
#include "modbus_rtu_driver/sim/simulator.h"
#include "test_sim_helpers.h"

using namespace modbus_rtu_driver;
using namespace modbus_rtu_driver::simtest;

namespace {

// Control commands that put a device in the state a printed read reply shows.
std::vector<std::string> prepare(const GoldenFrame& g, const Request& r) {
  if (!isReadFunction(r.function)) return {};
  const Bytes& reply = g.response;
  std::string table = r.function == FunctionCode::kReadCoils            ? "coil"
                      : r.function == FunctionCode::kReadDiscreteInputs ? "discrete_input"
                      : r.function == FunctionCode::kReadInputRegisters ? "input_register"
                                                                        : "holding_register";
  uint16_t address = r.address;
  if (table == "holding_register" && address != 0x80 && address != 0x03E8) return {};
  if (address == 0x03E8) address = 0x03E9;  // the stored baud code is written there
  std::string values;
  for (uint16_t i = 0; i < r.count; ++i)
    values +=
        " " + std::to_string(isBitFunction(r.function) ? (reply[3 + i / 8] >> (i % 8)) & 1
                                                       : reply[3 + 2 * i] << 8 | reply[4 + 2 * i]);
  return {"set #0 " + table + " " + std::to_string(address) + values};
}

}  // namespace

TEST(SimLine, EveryPrintedReplyByteForByteOverThePty) {
  int compared = 0;
  for (const auto& g : loadGoldenFrames(GOLDEN_FRAMES_PATH)) {
    if (g.response.empty() || g.device == "dm500_master") continue;
    Line line({{g.device, g.device == "lc_relay8" ? 255 : 1}});
    const auto request = decodeRequest(g.request);
    ASSERT_TRUE(request.has_value()) << g.meaning;
    for (const std::string& c : prepare(g, *request)) ASSERT_EQ(line(c), "ok") << c;
    PtyClient client(line.link());
    EXPECT_EQ(client.exchange(g.request, g.response.size()), toHex(g.response)) << g.meaning;
    ++compared;
  }
  EXPECT_EQ(compared, 37);
}

TEST(SimLine, SilenceForBadCrcAndNobodyResyncAfterNoise) {
  Line line({{"ld58a08", 1}, {"yespeed_pdu", 2}});
  PtyClient client(line.link());
  const Bytes good = encodeRequest(Request::readHoldingRegisters(2, 0, 3));
  const std::string reply =
      toHex(encodeReply(Request::readHoldingRegisters(2, 0, 3), {2500, 2000, 1600}));
  EXPECT_EQ(client.exchange(good, 11), reply);
  Bytes bad = good;
  bad.back() ^= 1;
  EXPECT_EQ(client.exchange(bad), "") << "bad CRC: silence";
  EXPECT_EQ(client.exchange("01 01 00 00 00 01 31 CA"), "") << "the PDU manual's misprinted CRC";
  EXPECT_EQ(client.exchange(encodeRequest(Request::readCoils(9, 0, 8))), "") << "nobody at 9";
  Bytes noisy{0x55, 0xAA, 0x13, 0x02};
  noisy.insert(noisy.end(), good.begin(), good.end());
  EXPECT_EQ(client.exchange(noisy, 11), reply) << "the valid frame after the noise";
  Bytes two = encodeRequest(Request::readCoils(1, 0, 8));
  two.insert(two.end(), good.begin(), good.end());
  const std::string coils =
      toHex(encodeReply(Request::readCoils(1, 0, 8), std::vector<uint16_t>(8)));
  EXPECT_EQ(client.exchange(two, 6 + 11), coils + " " + reply) << "back to back";
  // An unknown function: exception 01 from the device addressed, silence elsewhere.
  Bytes unknown{0x02, 0x2B, 0x0E, 0x01, 0x00};
  appendCrc(unknown);
  EXPECT_EQ(client.exchange(unknown, 5), exceptionHex(2, 0x2B, kIllegalFunction));
  unknown[0] = 9;
  unknown.resize(unknown.size() - 2);
  appendCrc(unknown);
  EXPECT_EQ(client.exchange(unknown), "");
  // A known function whose byte count does not match its quantity: exception 03.
  Bytes odd{0x02, 0x10, 0x00, 0x00, 0x00, 0x02, 0x02, 0x0A, 0x28};
  appendCrc(odd);
  EXPECT_EQ(client.exchange(odd, 5), exceptionHex(2, 0x10, kIllegalDataValue));
  const std::string frames = line("frames");  // ok RECEIVED ANSWERED DROPPED
  unsigned received = 0, answered = 0, dropped = 0;
  ASSERT_EQ(std::sscanf(frames.c_str(), "ok %u %u %u", &received, &answered, &dropped), 3);
  EXPECT_EQ(received, 8u);
  EXPECT_EQ(answered, 6u);
  EXPECT_GE(dropped, 3u);
}

TEST(SimLine, BroadcastsAreAppliedByAllAndAnsweredByNone) {
  Line line({{"lc_relay8", 255}, {"ld58a08", 1}, {"yespeed_pdu", 2}, {"lc_relay8", 254}});
  PtyClient client(line.link());
  EXPECT_EQ(client.exchange(encodeRequest(Request::writeSingleCoil(0, 3, true))), "");
  // Silence is all a broadcast gets: wait until the simulator has read it before looking.
  ASSERT_TRUE(line.tookFrames(1));
  EXPECT_EQ(line("get 255 coil 3"), "ok 1");
  EXPECT_EQ(line("get 1 coil 3"), "ok 1");
  EXPECT_EQ(line("get 2 coil 3"), "ok 1");
  EXPECT_EQ(line("get 254 coil 3"), "ok 1");
  EXPECT_EQ(client.exchange(encodeRequest(Request::writeSingleRegister(0, 0xFC, 2))), "");
  ASSERT_TRUE(line.tookFrames(2));
  EXPECT_EQ(line("get 1 holding_register 252"), "ok 2");
}

// Issue #13/8: what the commissioning tool's "alone on the bus" prevents. The LC board's address
// commands at 0 reach every device: every LC board takes them and answers, the answers collide,
// and every other device sees a broadcast write to its register 0.
TEST(SimLine, TheLcAddressCommandAtZeroReachesEveryBoardAndTheRepliesCollide) {
  Line line({{"lc_relay8", 255}, {"ld58a08", 1}, {"yespeed_pdu", 2}, {"lc_relay8", 254}});
  PtyClient client(line.link());
  // Reading the address: both boards answer at once; no valid frame comes back.
  const std::string read = client.exchange("00 03 00 00 00 01 85 DB");
  const Bytes garbled_read = hex(read);
  EXPECT_FALSE(garbled_read.empty()) << "the boards do answer";
  EXPECT_FALSE(hasValidCrc(garbled_read)) << read;
  EXPECT_NE(read, "00 03 02 00 FF C5 C4");
  // Setting it to 200 changes both boards; the echo is garbled as well.
  const Bytes set = encodeRequest(Request::writeMultipleRegisters(0, 0, {200}));
  const std::string echo = client.exchange(set);
  EXPECT_FALSE(echo.empty());
  EXPECT_FALSE(hasValidCrc(hex(echo))) << echo;
  EXPECT_EQ(line("info"),
            "ok #0:lc_relay8:200:9600:N #1:ld58a08:1:9600:N #2:yespeed_pdu:2:9600:N "
            "#3:lc_relay8:200:9600:N");
  EXPECT_EQ(line("get 1 holding_register 0"), "ok 200") << "the LD58A08 took 200 as CH0's period";
  EXPECT_EQ(line("get 2 holding_register 0"), "ok 2500")
      << "the PDU refuses 20.0 V as over-voltage";
}

TEST(SimLine, ABoardAloneAnswersItsAddressCommandsCleanly) {
  Line line({{"lc_relay8", 255}});
  PtyClient client(line.link());
  EXPECT_EQ(client.exchange("00 03 00 00 00 01 85 DB", 7), "00 03 02 00 FF C5 C4");
  const Bytes set = encodeRequest(Request::writeMultipleRegisters(0, 0, {200}));
  EXPECT_EQ(client.exchange(set, set.size()), toHex(set));
  EXPECT_EQ(line("info"), "ok #0:lc_relay8:200:9600:N");
  Line without_lc({{"ld58a08", 1}});
  PtyClient other(without_lc.link());
  EXPECT_EQ(other.exchange("00 03 00 00 00 01 85 DB"), "");
}

TEST(SimLine, CollidingRepliesAreNeverAValidFrame) {
  const Bytes a = hex("00 10 00 00 00 01 02 00 FF EB 80");
  const Bytes garbled = collideReplies({a, a});  // the same echo from two boards
  EXPECT_EQ(garbled.size(), a.size() + 1);
  EXPECT_FALSE(hasValidCrc(garbled));
  EXPECT_NE(Bytes(garbled.begin(), garbled.begin() + static_cast<long>(a.size())), a);
  const Bytes b = hex("00 03 02 00 FF C5 C4"), c = hex("00 03 02 00 FE 04 04");
  EXPECT_FALSE(hasValidCrc(collideReplies({b, c})));
}

TEST(SimLine, DevicesHearOnlyTheirOwnBaudAndParity) {
  Line line({{"ld58a08", 1}});
  PtyClient client(line.link(), B19200);
  const Bytes read = encodeRequest(Request::readHoldingRegisters(1, 0xFD, 1));
  const std::string at1 = toHex(encodeReply(Request::readHoldingRegisters(1, 0xFD, 1), {1}));
  // Before the client changes its settings, the simulator has read the request at the old
  // ones (silence alone does not say so on a loaded machine).
  EXPECT_EQ(client.exchange(read), "") << "19200: not understood";
  ASSERT_TRUE(line.tookFrames(1));
  client.configure(B9600, 'E');
  EXPECT_EQ(client.exchange(read), "") << "even parity: not understood";
  ASSERT_TRUE(line.tookFrames(2));
  client.configure(B9600);
  EXPECT_EQ(client.exchange(read, 7), at1);
  ASSERT_EQ(line("set 1 holding_register 254 4 1"), "ok");  // 19200, even: at power-on
  EXPECT_EQ(client.exchange(read, 7), at1);
  ASSERT_EQ(line("power_cycle"), "ok");
  EXPECT_EQ(client.exchange(read), "");
  ASSERT_TRUE(line.tookFrames(5));
  client.configure(B19200);
  EXPECT_EQ(client.exchange(read), "");
  ASSERT_TRUE(line.tookFrames(6));
  client.configure(B19200, 'E');
  EXPECT_EQ(client.exchange(read, 7), at1);
  EXPECT_EQ(line("info"), "ok #0:ld58a08:1:19200:E");
}

TEST(SimLine, ReturnDelayReallyDelaysTheReply) {
  Line line({{"ld58a08", 1}});
  PtyClient client(line.link());
  ASSERT_EQ(client.exchange("01 06 00 FC 00 05 89 F9", 8), "01 06 00 FC 00 05 89 F9");
  const auto t0 = SimClock::now();
  EXPECT_EQ(client.exchange(encodeRequest(Request::readCoils(1, 0, 8)), 6, 2000ms),
            toHex(encodeReply(Request::readCoils(1, 0, 8), std::vector<uint16_t>(8))));
  EXPECT_GE(SimClock::now() - t0, 195ms) << "5 x 40 ms";
}

// Issue 24/8: an LD58A08 takes its settings frames at 0xFF whoever else is at 255; with an LC
// board at its factory address 255 both answer and the replies garble on the line (the node
// refuses that configuration). Either board alone answers cleanly.
TEST(SimLine, AnLcBoardAt255AndAnLd58a08At0xFFBothAnswerAndCollide) {
  for (bool lc_first : {true, false}) {
    std::vector<SimulatorConfig::Entry> devices{{"lc_relay8", 255}, {"ld58a08", 1}};
    if (!lc_first) std::swap(devices[0], devices[1]);
    Line line(devices);
    PtyClient client(line.link());
    // LC: exception 02 (5 bytes), LD58A08: its address (7 bytes); on the line: 8 garbled bytes.
    const std::string garbled = client.exchange("FF 03 00 FD 00 01 00 24", 8);
    EXPECT_EQ(hex(garbled).size(), 8u) << garbled;
    EXPECT_FALSE(hasValidCrc(hex(garbled))) << garbled;
    EXPECT_NE(garbled, exceptionHex(0xFF, 0x03, kIllegalDataAddress));
    // Frames only the LC board takes at 255 (its relays) stay clean.
    EXPECT_EQ(client.exchange(encodeRequest(Request::readCoils(255, 0, 8)), 6),
              toHex(encodeReply(Request::readCoils(255, 0, 8), std::vector<uint16_t>(8))));
    ASSERT_EQ(line("silence 255 1"), "ok");
    EXPECT_EQ(client.exchange("FF 03 00 FD 00 01 00 24", 7), "FF 03 02 00 01 50 50");
    ASSERT_EQ(line("silence 255 0"), "ok");
    ASSERT_EQ(line("silence 1 1"), "ok");
    EXPECT_EQ(client.exchange("FF 03 00 FD 00 01 00 24", 5),
              exceptionHex(0xFF, 0x03, kIllegalDataAddress))
        << "the LC board alone";
  }
}

TEST(SimLine, PacedLineTakesTheWireTimeAndSendsAtTheCharacterRate) {
  // Only lower bounds: a loaded machine can make everything later, never earlier.
  Line line({{"yespeed_pdu", 2}}, /*pace=*/true, 1200);
  PtyClient client(line.link(), B1200);
  const Bytes request = encodeRequest(Request::readHoldingRegisters(2, 0, 1));
  client.receive(256, 0ms);
  const auto t0 = SimClock::now();
  client.send(request);
  SimClock::time_point first{}, last{};
  Bytes in;
  while (in.size() < 7 && SimClock::now() - t0 < 3s) {
    const Bytes part = client.receive(1, 3000ms);
    if (part.empty()) break;
    if (in.empty()) first = SimClock::now();
    last = SimClock::now();
    in.insert(in.end(), part.begin(), part.end());
  }
  ASSERT_EQ(toHex(in), toHex(encodeReply(Request::readHoldingRegisters(2, 0, 1), {2500})));
  // 1200 baud 8N1: 8.33 ms a character, t3.5 = 29.2 ms. Request 8 characters, reply 7.
  EXPECT_GE(first - t0, 100ms) << "request wire time, t3.5 and the first reply character";
  // Written at once when due, the reply would be complete at ~104 ms.
  EXPECT_GE(last - t0, 150ms) << "all 15 characters and the gap";
}

TEST(SimLine, AStaleLinkIsReplacedAndStopRemovesLinkAndSocket) {
  ScratchDir dir;
  ASSERT_EQ(symlink("/nonexistent/pts", (dir / "tty").c_str()), 0);
  SimulatorConfig config;
  config.devices = {{"ld58a08", 1}};
  SimulatorOptions options;
  options.link = dir / "tty";
  Simulator sim(config, options);
  std::string error;
  ASSERT_TRUE(sim.start(&error)) << error;
  char target[256] = {};
  ASSERT_GT(readlink(options.link.c_str(), target, sizeof target - 1), 0);
  EXPECT_EQ(std::string(target).rfind("/dev/pts/", 0), 0u) << target;
  struct stat st {};
  EXPECT_EQ(stat((dir / "tty.ctl").c_str(), &st), 0);
  EXPECT_TRUE(S_ISSOCK(st.st_mode));
  sim.stop();
  EXPECT_NE(lstat(options.link.c_str(), &st), 0);
  EXPECT_NE(lstat((dir / "tty.ctl").c_str(), &st), 0);
}
