// The simulated devices: the manuals' frames, time behaviour, rules, power cycle, state file,
// and the line over a real pty.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <termios.h>
#include <unistd.h>

#include <fstream>
#include <set>
#include <thread>

#include "golden_frames.h"
#include "modbus_rtu_driver/sim/sim_lc_relay8.h"
#include "modbus_rtu_driver/sim/sim_ld58a08.h"
#include "modbus_rtu_driver/sim/sim_yespeed_pdu.h"
#include "modbus_rtu_driver/sim/simulator.h"

using namespace modbus_rtu_driver;
using namespace std::chrono_literals;

namespace {

std::optional<Bytes> ask(SimDevice& d, const std::string& hex) {
  const Bytes frame = *fromHex(hex);
  auto request = decodeRequest(frame);
  EXPECT_TRUE(request.has_value()) << hex;
  if (request->slave == 0)
    if (auto* lc = dynamic_cast<SimLcRelay8*>(&d)) return lc->handleAtZero(*request);
  EXPECT_TRUE(d.answersTo(request->slave, &*request)) << hex;
  return d.handle(*request, SimClock::now());
}

// Puts a device into the state a printed read reply shows, so the reply can be compared.
void prepareFor(SimDevice& d, const Request& r, const Bytes& reply) {
  const auto now = SimClock::now();
  if (r.function == FunctionCode::kReadCoils || r.function == FunctionCode::kReadDiscreteInputs) {
    const Table t = r.function == FunctionCode::kReadCoils ? Table::kCoil : Table::kDiscreteInput;
    for (uint16_t i = 0; i < r.count; ++i)
      d.setDirect(t, static_cast<uint16_t>(r.address + i), (reply[3 + i / 8] >> (i % 8)) & 1, now);
  } else if (r.function == FunctionCode::kReadInputRegisters) {
    for (uint16_t i = 0; i < r.count; ++i)
      d.setDirect(Table::kInputRegister, static_cast<uint16_t>(r.address + i),
                  static_cast<uint16_t>(reply[3 + 2 * i] << 8 | reply[4 + 2 * i]), now);
  } else if (r.function == FunctionCode::kReadHoldingRegisters && r.address == 0x0080) {
    d.setDirect(Table::kHolding, 0x0080, static_cast<uint16_t>(reply[4]), now);
  }
}

}  // namespace

TEST(SimDevices, AnswerEveryPrintedReplyByteForByte) {
  int compared = 0;
  for (const auto& g : loadGoldenFrames(GOLDEN_FRAMES_PATH)) {
    if (g.response.empty() || g.device == "dm500_master" || g.request_crc_printed_wrong) continue;
    const auto request = decodeRequest(g.request);
    ASSERT_TRUE(request.has_value()) << g.meaning;
    // The LC board's baud read shows 19200 (code 4): that board runs at 19200.
    SimLineSettings line;
    if (request->address == 0x03E8) line.baud = 19200;
    const uint8_t address = g.device == "lc_relay8" ? 255 : 1;
    auto device = makeSimDevice(g.device, address, line);
    ASSERT_TRUE(device) << g.device;
    prepareFor(*device, *request, g.response);
    const auto reply = ask(*device, toHex(g.request));
    ASSERT_TRUE(reply.has_value()) << g.meaning;
    EXPECT_EQ(toHex(*reply), toHex(g.response)) << g.meaning;
    ++compared;
  }
  EXPECT_GE(compared, 30);
}

TEST(SimLd58a08, SlowChannelCountsPulsesAndStops) {
  SimLd58a08 d(1, {});
  const auto t0 = SimClock::now();
  // period 0.2 s, on 0.1 s, 3 pulses
  ASSERT_TRUE(d.write(Table::kHolding, 0x0010, {2, 1, 3}, t0) == 0);
  uint16_t v = 0;
  d.read(Table::kCoil, 1, t0 + 50ms, &v);
  EXPECT_EQ(v, 1);  // first on-phase
  d.read(Table::kCoil, 1, t0 + 150ms, &v);
  EXPECT_EQ(v, 0);  // off-phase
  d.read(Table::kHolding, 0x0012, t0 + 250ms, &v);
  EXPECT_EQ(v, 2);  // one pulse done, two to go
  d.read(Table::kHolding, 0x0012, t0 + 650ms, &v);
  EXPECT_EQ(v, 0);  // all done: PWM off
  d.read(Table::kCoil, 1, t0 + 650ms, &v);
  EXPECT_EQ(v, 0);
}

TEST(SimLd58a08, FastChannelRunsForItsOutputTime) {
  SimLd58a08 d(1, {});
  const auto t0 = SimClock::now();
  ASSERT_EQ(d.write(Table::kHolding, 0x0070, {10000, 30, 3}, t0), 0);  // 0.3 s
  uint16_t v = 0;
  d.read(Table::kCoil, 7, t0 + 100ms, &v);
  EXPECT_EQ(v, 1);
  d.read(Table::kHolding, 0x0072, t0 + 100ms, &v);
  EXPECT_EQ(v, 2);
  d.read(Table::kCoil, 7, t0 + 400ms, &v);
  EXPECT_EQ(v, 0);
  d.read(Table::kHolding, 0x0072, t0 + 400ms, &v);
  EXPECT_EQ(v, 0);
}

TEST(SimLd58a08, SpecialRegisters) {
  SimLd58a08 d(1, {});
  const auto now = SimClock::now();
  uint16_t v = 0;
  EXPECT_EQ(d.write(Table::kHolding, 0x00FC, {5}, now), 0);
  EXPECT_DOUBLE_EQ(d.replyDelay(), 0.2);
  EXPECT_EQ(d.write(Table::kHolding, 0x00FC, {0x20}, now), 0);  // over 25: back to 0
  EXPECT_DOUBLE_EQ(d.replyDelay(), 0.0);
  EXPECT_EQ(d.write(Table::kHolding, 0x00FD, {0}, now), kIllegalDataValue);
  EXPECT_EQ(d.write(Table::kHolding, 0x00FA, {2}, now), kIllegalDataValue);
  EXPECT_EQ(d.read(Table::kHolding, 0x0005, now, &v), kIllegalDataAddress);
  EXPECT_EQ(d.read(Table::kDiscreteInput, 0, now, &v), kIllegalFunction);
  // Baud and parity wait for a power cycle; parity 3 comes back as 0.
  EXPECT_EQ(d.write(Table::kHolding, 0x00FE, {7}, now), 0);
  EXPECT_EQ(d.write(Table::kHolding, 0x00FF, {3}, now), 0);
  EXPECT_EQ(d.line().baud, 9600);
  d.powerCycle();
  EXPECT_EQ(d.line().baud, 115200);
  EXPECT_EQ(d.line().parity, 'N');
  // Factory reset through 0xFF.
  EXPECT_EQ(d.write(Table::kHolding, 0x00FD, {7}, now), 0);
  EXPECT_EQ(d.write(Table::kHolding, 0x00FB, {0}, now), 0);
  EXPECT_EQ(d.address(), 1);
  d.powerCycle();
  EXPECT_EQ(d.line().baud, 9600);
}

TEST(SimLd58a08, SavedPwmSurvivesAPowerCycleOnlyWhenEnabled) {
  SimLd58a08 d(1, {});
  const auto now = SimClock::now();
  uint16_t v = 0;
  ASSERT_EQ(d.write(Table::kHolding, 0x0020, {100, 50, 0xFFFF}, now), 0);
  d.powerCycle();
  d.read(Table::kHolding, 0x0020, now, &v);
  EXPECT_EQ(v, 0);
  ASSERT_EQ(d.write(Table::kHolding, 0x00FA, {1}, now), 0);
  ASSERT_EQ(d.write(Table::kHolding, 0x0020, {100, 50, 0xFFFF}, now), 0);
  d.powerCycle();
  d.read(Table::kHolding, 0x0020, now, &v);
  EXPECT_EQ(v, 100);
}

TEST(SimLcRelay8, FlashesRevertByThemselves) {
  SimLcRelay8 d(255, {});
  const auto t0 = SimClock::now();
  ASSERT_EQ(d.write(Table::kHolding, 0x0003 + 5 * 2, {4, 2}, t0), 0);  // close #3 for 0.2 s
  uint16_t v = 0;
  d.read(Table::kCoil, 2, t0 + 100ms, &v);
  EXPECT_EQ(v, 1);
  d.read(Table::kCoil, 2, t0 + 250ms, &v);
  EXPECT_EQ(v, 0);
  ASSERT_EQ(d.write(Table::kCoil, 5, {1}, t0), 0);
  ASSERT_EQ(d.write(Table::kHolding, 0x0003 + 5 * 5, {2, 3}, t0), 0);  // open #6 for 0.3 s
  d.read(Table::kCoil, 5, t0 + 100ms, &v);
  EXPECT_EQ(v, 0);
  d.read(Table::kCoil, 5, t0 + 350ms, &v);
  EXPECT_EQ(v, 1);
  EXPECT_EQ(d.write(Table::kHolding, 0x0003, {7, 3}, t0), kIllegalDataValue);  // unknown mode
  EXPECT_EQ(d.write(Table::kHolding, 0x03E9, {5}, t0), kIllegalDataValue);     // baud code 2-4
}

TEST(SimLcRelay8, AddressThroughZeroAndInputsFromOutside) {
  SimLcRelay8 d(255, {});
  Request set = Request::writeMultipleRegisters(0, 0, {7});
  auto reply = ask(d, toHex(encodeRequest(set)));
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(d.address(), 7);
  reply = ask(d, "00 03 00 00 00 01 85 DB");
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(toHex(*reply),
            toHex(encodeReply(*decodeRequest(*fromHex("00 03 00 00 00 01 85 DB")), {7})));
  EXPECT_EQ(d.setDirect(Table::kDiscreteInput, 3, 1, SimClock::now()), 0);
  uint16_t v = 0;
  d.read(Table::kDiscreteInput, 3, SimClock::now(), &v);
  EXPECT_EQ(v, 1);
}

TEST(SimYespeedPdu, LimitRulesAndMovingTelemetry) {
  SimYespeedPdu d(1, {});
  const auto t0 = SimClock::now();
  EXPECT_EQ(d.write(Table::kHolding, 0, {2600, 1600, 700}, t0), 0);
  EXPECT_EQ(d.write(Table::kHolding, 0, {1800}, t0), kIllegalDataValue);  // over > 180 V
  EXPECT_EQ(d.write(Table::kHolding, 1, {2800}, t0), kIllegalDataValue);  // under < 280 V
  EXPECT_EQ(d.write(Table::kHolding, 2, {500}, t0), kIllegalDataValue);   // 5 A < current
  EXPECT_EQ(d.write(Table::kHolding, 2, {2000}, t0), kIllegalDataValue);  // current < 20 A
  EXPECT_EQ(d.write(Table::kHolding, 0, {1900, 1950, 700}, t0), kIllegalDataValue);  // over > under
  uint16_t v = 0;
  d.read(Table::kHolding, 0, t0, &v);
  EXPECT_EQ(v, 2600);  // refused writes changed nothing
  uint16_t i_off = 0, i_on = 0, volts = 0;
  d.read(Table::kInputRegister, 3, t0, &i_off);
  ASSERT_EQ(d.write(Table::kCoil, 0, {1, 1, 1, 1}, t0), 0);
  d.read(Table::kInputRegister, 3, t0, &i_on);
  EXPECT_GT(i_on, i_off + 300);  // four loads draw current
  d.read(Table::kInputRegister, 2, t0, &volts);
  EXPECT_GT(volts, 2100);
  EXPECT_LT(volts, 2300);
  std::set<uint16_t> seen;
  for (int s = 0; s < 20; ++s) {
    d.read(Table::kInputRegister, 2, t0 + std::chrono::milliseconds(700 * s), &v);
    seen.insert(v);
  }
  EXPECT_GT(seen.size(), 3u) << "voltage moves over time";
}

TEST(Simulator, StateFileSurvivesARestartAndLineSettingsAreChecked) {
  const std::string dir = "/tmp/modbus_rtu_gtest_sim_" + std::to_string(getpid());
  SimulatorConfig config;
  config.devices = {{"ld58a08", 1}};
  SimulatorOptions options;
  options.link = dir + "/tty";
  options.state_file = dir + "/state.yaml";
  {
    Simulator sim(config, options);
    ASSERT_TRUE(sim.start(nullptr));
    EXPECT_EQ(sim.command("set 1 holding 253 9"), "ok");
    EXPECT_EQ(sim.command("set 9 holding 254 4"), "ok");
    EXPECT_EQ(sim.command("power_cycle"), "ok");
    EXPECT_EQ(sim.command("info"), "ok #0:ld58a08:9:19200:N");
  }
  Simulator again(config, options);
  ASSERT_TRUE(again.start(nullptr));
  EXPECT_EQ(again.command("info"), "ok #0:ld58a08:9:19200:N");
  EXPECT_EQ(again.command("get 9 holding 253"), "ok 9");
  EXPECT_EQ(again.command("bogus"), "error no device ''");
}

TEST(Simulator, GarbageBadCrcAndUnknownAddressesOverARealPty) {
  SimulatorConfig config;
  config.devices = {{"yespeed_pdu", 2}};
  SimulatorOptions options;
  options.link = "/tmp/modbus_rtu_gtest_line_" + std::to_string(getpid()) + "/tty";
  Simulator sim(config, options);
  ASSERT_TRUE(sim.start(nullptr));
  const int fd = open(options.link.c_str(), O_RDWR | O_NOCTTY);
  ASSERT_GE(fd, 0);
  termios tio{};
  tcgetattr(fd, &tio);
  cfmakeraw(&tio);
  cfsetispeed(&tio, B9600);
  cfsetospeed(&tio, B9600);
  tcsetattr(fd, TCSANOW, &tio);
  auto exchange = [&](const Bytes& out, int wait_ms) {
    tcflush(fd, TCIFLUSH);
    EXPECT_EQ(write(fd, out.data(), out.size()), static_cast<ssize_t>(out.size()));
    std::this_thread::sleep_for(std::chrono::milliseconds(wait_ms));
    uint8_t buf[64];
    Bytes in;
    fcntl(fd, F_SETFL, O_NONBLOCK);
    ssize_t n;
    while ((n = read(fd, buf, sizeof buf)) > 0) in.insert(in.end(), buf, buf + n);
    return in;
  };
  const Bytes good = encodeRequest(Request::readHoldingRegisters(2, 0, 3));
  EXPECT_EQ(toHex(exchange(good, 100)),
            toHex(encodeReply(Request::readHoldingRegisters(2, 0, 3), {2500, 2000, 1600})));
  Bytes bad = good;
  bad.back() ^= 1;
  EXPECT_TRUE(exchange(bad, 100).empty()) << "bad CRC: silence";
  EXPECT_TRUE(exchange(encodeRequest(Request::readCoils(9, 0, 8)), 100).empty()) << "nobody at 9";
  Bytes noisy{0x55, 0xAA, 0x13};
  noisy.insert(noisy.end(), good.begin(), good.end());
  EXPECT_EQ(exchange(noisy, 100).size(), 11u) << "a valid frame after noise is answered";
  Bytes unknown{0x02, 0x2B, 0x0E, 0x01};
  appendCrc(unknown);
  EXPECT_EQ(toHex(exchange(unknown, 100)), toHex(encodeException(2, 0x2B, kIllegalFunction)));
  close(fd);
}
