// The simulated LD58A08: outputs and their mirror, PWM registers and their rules, pulses and
// output times over (simulated and real) time, the special registers, power cycle and state.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <thread>

#include "modbus_rtu_driver/sim/sim_ld58a08.h"
#include "test_sim_helpers.h"

using namespace modbus_rtu_driver;
using namespace modbus_rtu_driver::simtest;

namespace {

constexpr uint8_t kFc03 = 0x03, kFc06 = 0x06, kFc10 = 0x10;

std::vector<uint16_t> regs(SimDevice& d, uint16_t address, int count,
                           SimClock::time_point now = SimClock::now()) {
  std::vector<uint16_t> out;
  for (int i = 0; i < count; ++i) out.push_back(get(d, Table::kHoldingRegister, address + i, now));
  return out;
}

uint16_t coil(SimDevice& d, uint16_t ch, SimClock::time_point now = SimClock::now()) {
  return get(d, Table::kCoil, ch, now);
}

}  // namespace

TEST(SimLd58a08, CoilsAndTheMaskRegisterAreOneState) {
  SimLd58a08 d(1, {});
  EXPECT_EQ(ask(d, Request::writeSingleCoil(1, 5, true)), "01 05 00 05 FF 00 9C 3B");
  EXPECT_EQ(regs(d, 0x80, 1)[0], 0x20);
  EXPECT_EQ(ask(d, "01 06 00 80 00 09 48 24"), "01 06 00 80 00 09 48 24");
  EXPECT_EQ(coil(d, 0) + coil(d, 3) * 2 + coil(d, 5) * 4, 3) << "0x0080 replaced all 8 bits";
  ASSERT_FALSE(ask(d, Request::writeMultipleRegisters(1, 0x80, {0x7C})).empty());
  EXPECT_EQ(ask(d, "01 01 00 00 00 08 3D CC"), "01 01 01 7C 50 69");  // the manual's state
  // Outside the map and unsupported tables.
  EXPECT_EQ(ask(d, Request::readCoils(1, 0, 9)), exceptionHex(1, 0x01, kIllegalDataAddress));
  EXPECT_EQ(ask(d, Request::writeSingleCoil(1, 8, true)),
            exceptionHex(1, 0x05, kIllegalDataAddress));
  EXPECT_EQ(ask(d, Request::readDiscreteInputs(1, 0, 8)), exceptionHex(1, 0x02, kIllegalFunction));
  EXPECT_EQ(ask(d, Request::readInputRegisters(1, 0, 1)), exceptionHex(1, 0x04, kIllegalFunction));
  EXPECT_EQ(ask(d, Request::writeSingleRegister(1, 0x80, 0x100)),
            exceptionHex(1, kFc06, kIllegalDataValue));
}

TEST(SimLd58a08, EveryPwmRegisterReadsBackAndGapsAreIllegal) {
  SimLd58a08 d(1, {});
  for (uint16_t ch = 0; ch < 8; ++ch) {
    const uint16_t base = static_cast<uint16_t>(ch << 4);
    const std::vector<uint16_t> v =
        ch < 6 ? std::vector<uint16_t>{uint16_t(100 + ch), uint16_t(50 + ch), 0}
               : std::vector<uint16_t>{uint16_t(1000 * ch), uint16_t(10 * ch), 0};
    ASSERT_EQ(d.write(Table::kHoldingRegister, base, v, SimClock::now()), 0) << ch;
    EXPECT_EQ(regs(d, base, 3), v) << ch;
  }
  for (uint16_t a : {0x0003, 0x000F, 0x0073, 0x0081, 0x00F9, 0x0100}) {
    uint16_t v = 0;
    EXPECT_EQ(d.read(Table::kHoldingRegister, a, SimClock::now(), &v), kIllegalDataAddress) << a;
  }
  // A write running into a gap is refused whole.
  EXPECT_EQ(ask(d, Request::writeMultipleRegisters(1, 0x0001, {7, 8, 9})),
            exceptionHex(1, kFc10, kIllegalDataAddress));
  EXPECT_EQ(regs(d, 0x0000, 3), (std::vector<uint16_t>{100, 50, 0}));
  EXPECT_EQ(ask(d, Request::readHoldingRegisters(1, 0x00FA, 6)),
            toHex(encodeReply(Request::readHoldingRegisters(1, 0xFA, 6), {0, 0, 0, 1, 3, 0})));
}

TEST(SimLd58a08, PwmValuesOutsideTheManualAreRefusedAndChangeNothing) {
  SimLd58a08 d(1, {});
  const auto refused = [&](uint16_t address, const std::vector<uint16_t>& values) {
    const std::string reply = ask(d, Request::writeMultipleRegisters(1, address, values));
    return reply == exceptionHex(1, kFc10, kIllegalDataValue);
  };
  EXPECT_TRUE(refused(0x0010, {0, 0, 5}));            // period 0
  EXPECT_TRUE(refused(0x0010, {10, 11, 5}));          // on-time longer than the period
  EXPECT_TRUE(refused(0x0010, {10, 11}));             // ... even when not started
  EXPECT_TRUE(refused(0x0011, {0xFFFF}));             // on-time max is 6553.4 s
  EXPECT_TRUE(refused(0x0012, {3}));                  // start without a period
  EXPECT_TRUE(refused(0x0060, {20001, 50, 0xFFFF}));  // frequency 1-20000 Hz
  EXPECT_TRUE(refused(0x0060, {0}));
  EXPECT_TRUE(refused(0x0070, {1000, 101}));  // duty cycle 0-100 %
  EXPECT_TRUE(refused(0x0072, {0xFFFF}));     // start without a frequency
  EXPECT_EQ(regs(d, 0x10, 3), (std::vector<uint16_t>{0, 0, 0}));
  EXPECT_EQ(regs(d, 0x60, 3), (std::vector<uint16_t>{0, 0, 0}));
  // Staging one register at a time in any order is fine while the channel is stopped.
  EXPECT_EQ(d.write(Table::kHoldingRegister, 0x0011, {30}, SimClock::now()), 0);
  EXPECT_EQ(d.write(Table::kHoldingRegister, 0x0010, {20}, SimClock::now()), 0);
  EXPECT_TRUE(refused(0x0012, {1})) << "on-time 3 s > period 2 s cannot run";
  EXPECT_EQ(d.write(Table::kHoldingRegister, 0x0010, {40, 30, 1}, SimClock::now()), 0);
  EXPECT_TRUE(refused(0x0011, {41})) << "running: on-time stays within the period";
}

TEST(SimLd58a08, SlowChannelPulsesCountDownAndStop) {
  SimLd58a08 d(1, {});
  const auto t0 = SimClock::now();
  // Period 0.2 s, on 0.1 s, 3 pulses: on in [0, 0.1), off in [0.1, 0.2), ... done at 0.6 s.
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0010, {2, 1, 3}, t0), 0);
  int rising = 0;
  uint16_t last = 0, last_count = 3;
  for (int ms = 0; ms <= 800; ms += 10) {
    const auto t = t0 + std::chrono::milliseconds(ms) + 5ms;
    const uint16_t out = coil(d, 1, t), count = regs(d, 0x12, 1, t)[0];
    EXPECT_EQ(out, ms < 600 && ms % 200 < 100 ? 1 : 0) << ms << " ms";
    EXPECT_LE(count, last_count) << "counts down";
    rising += out && !last;
    last = out;
    last_count = count;
  }
  EXPECT_EQ(rising, 3);
  EXPECT_EQ(last_count, 0) << "register 0: stopped";
  EXPECT_EQ(ask(d, Request::writeSingleCoil(1, 1, true), t0 + 900ms), "01 05 00 01 FF 00 DD FA");
  EXPECT_EQ(coil(d, 1, t0 + 900ms), 1) << "a plain output again";
}

TEST(SimLd58a08, ContinuousPulsesRunUntilStoppedAndOverrideCoilWrites) {
  SimLd58a08 d(1, {});
  const auto t0 = SimClock::now();
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0000, {10, 5, 0xFFFF}, t0), 0);  // 1 s, 50 %
  EXPECT_EQ(regs(d, 0x02, 1, t0 + 3600s)[0], 0xFFFF);
  EXPECT_EQ(coil(d, 0, t0 + 3600s + 700ms), 0);
  EXPECT_EQ(d.write(Table::kCoil, 0, {1}, t0 + 3600s + 700ms), 0);
  EXPECT_EQ(coil(d, 0, t0 + 3600s + 700ms), 0) << "the PWM owns the output";
  EXPECT_EQ(coil(d, 0, t0 + 3601s + 200ms), 1);
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0002, {0}, t0 + 3601s + 300ms), 0);
  EXPECT_EQ(coil(d, 0, t0 + 3601s + 300ms), 0) << "stopping turns the output off";
  EXPECT_EQ(coil(d, 0, t0 + 3601s + 800ms), 0);
}

// Manual, 0x0080: the output status applies only with the channel's PWM enable register at 0.
// Every way of writing an output (FC05, FC15, FC06 / FC16 on 0x0080) leaves a PWM channel to
// its PWM, and still sets the plain channels of the same write.
TEST(SimLd58a08, OutputWritesDoNotMoveAChannelWhosePwmRuns) {
  SimLd58a08 d(1, {});
  const auto t0 = SimClock::now();
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0020, {10, 5, 0xFFFF}, t0),
            0);  // 2: on 0.5 s of 1 s
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0060, {1000, 0, 0xFFFF}, t0),
            0);  // 6: 0 % duty, off
  const std::vector<Request> writes = {
      Request::writeSingleCoil(1, 2, true),
      Request::writeSingleCoil(1, 6, true),
      Request::writeMultipleCoils(1, 0, {true, true, true, true, true, true, true, true}),
      Request::writeSingleRegister(1, 0x80, 0xFF),
      Request::writeMultipleRegisters(1, 0x80, {0xFF}),
  };
  auto second = t0;
  for (const Request& w : writes) {
    const std::string frame = toHex(encodeRequest(w));
    const auto off_phase = second + 700ms, on_phase = second + 1200ms;
    second += 1s;
    ASSERT_EQ(d.write(Table::kHoldingRegister, 0x80, {0}, off_phase), 0);
    EXPECT_FALSE(ask(d, w, off_phase).empty()) << "the board acknowledges: " << frame;
    EXPECT_EQ(coil(d, 2, off_phase), 0) << "the PWM's off phase, not the write: " << frame;
    EXPECT_EQ(coil(d, 6, off_phase), 0) << "0 % duty, not the write: " << frame;
    if (w.function != FunctionCode::kWriteSingleCoil) {
      EXPECT_EQ(coil(d, 0, off_phase), 1) << "a plain channel takes it: " << frame;
    }
    EXPECT_EQ(coil(d, 2, on_phase), 1) << "then the PWM's on phase: " << frame;
    // Off does not hold an output that the PWM has on either.
    ASSERT_EQ(d.write(Table::kCoil, 2, {0}, on_phase), 0);
    EXPECT_EQ(coil(d, 2, on_phase), 1) << frame;
  }
  // Enable 0: a plain output again, written as asked.
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0022, {0}, second), 0);
  ASSERT_EQ(d.write(Table::kCoil, 2, {1}, second), 0);
  EXPECT_EQ(coil(d, 2, second + 10s + 700ms), 1);
  EXPECT_EQ(regs(d, 0x22, 1, second + 10s)[0], 0);
}

TEST(SimLd58a08, NewTimingWhileRunningKeepsThePulsesLeft) {
  SimLd58a08 d(1, {});
  const auto t0 = SimClock::now();
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0020, {10, 5, 10}, t0), 0);  // 10 pulses of 1 s
  EXPECT_EQ(regs(d, 0x22, 1, t0 + 3500ms)[0], 7);
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0020, {2, 1}, t0 + 3500ms), 0);  // now 0.2 s each
  EXPECT_EQ(regs(d, 0x22, 1, t0 + 3500ms)[0], 7);
  EXPECT_EQ(regs(d, 0x22, 1, t0 + 3500ms + 1300ms)[0], 1);
  EXPECT_EQ(regs(d, 0x22, 1, t0 + 3500ms + 1450ms)[0], 0);
}

TEST(SimLd58a08, FastChannelRunsForItsOutputTime) {
  SimLd58a08 d(1, {});
  const auto t0 = SimClock::now();
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0070, {10000, 30, 3}, t0), 0);  // 0.3 s
  EXPECT_EQ(coil(d, 7, t0 + 10ms), 1) << "on while it runs";
  EXPECT_EQ(regs(d, 0x72, 1, t0 + 10ms)[0], 3);
  EXPECT_EQ(regs(d, 0x72, 1, t0 + 150ms)[0], 2);
  EXPECT_EQ(regs(d, 0x72, 1, t0 + 250ms)[0], 1);
  EXPECT_EQ(regs(d, 0x72, 1, t0 + 310ms)[0], 0);
  EXPECT_EQ(coil(d, 7, t0 + 310ms), 0);
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0060, {2000, 0, 0xFFFF}, t0), 0);
  EXPECT_EQ(coil(d, 6, t0 + 1h), 0) << "a 0 % duty cycle never drives the output";
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0061, {55}, t0 + 1h), 0);
  EXPECT_EQ(coil(d, 6, t0 + 1h), 1);
  EXPECT_EQ(regs(d, 0x62, 1, t0 + 2h)[0], 0xFFFF) << "continuous";
}

TEST(SimLd58a08, PulsesAndOutputTimeOverRealTime) {
  SimLd58a08 d(1, {});
  const auto t0 = SimClock::now();
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0030, {2, 1, 5}, t0), 0);     // 5 pulses of 0.2 s
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0060, {500, 50, 3}, t0), 0);  // 0.3 s output time
  EXPECT_EQ(coil(d, 3, t0 + 10ms), 1);
  EXPECT_EQ(coil(d, 6, t0 + 10ms), 1);
  uint16_t last = 5;
  SimClock::time_point slow_done{}, fast_done{};
  while (SimClock::now() - t0 < 5s &&
         (slow_done == SimClock::time_point{} || fast_done == SimClock::time_point{})) {
    const auto now = SimClock::now();
    const uint16_t left = regs(d, 0x32, 1, now)[0];
    EXPECT_LE(left, last);
    last = left;
    if (left == 0 && slow_done == SimClock::time_point{}) slow_done = now;
    if (regs(d, 0x62, 1, now)[0] == 0 && fast_done == SimClock::time_point{}) fast_done = now;
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_NE(slow_done, SimClock::time_point{}) << "5 pulses of 0.2 s ended within 5 s";
  ASSERT_NE(fast_done, SimClock::time_point{}) << "0.3 s output time ended within 5 s";
  EXPECT_GE(slow_done - t0, 1000ms);
  EXPECT_GE(fast_done - t0, 300ms);
  EXPECT_EQ(coil(d, 3) + coil(d, 6), 0);
}

TEST(SimLd58a08, ReturnDelayAndItsLimit) {
  SimLd58a08 d(1, {});
  EXPECT_EQ(ask(d, "01 06 00 FC 00 05 89 F9"), "01 06 00 FC 00 05 89 F9");
  EXPECT_DOUBLE_EQ(d.replyDelay(), 0.2);
  EXPECT_EQ(regs(d, 0xFC, 1)[0], 5);
  EXPECT_EQ(ask(d, "01 06 00 FC 00 20 48 22"), "01 06 00 FC 00 20 48 22");
  EXPECT_DOUBLE_EQ(d.replyDelay(), 0.0) << "over 25: back to 0";
  EXPECT_EQ(regs(d, 0xFC, 1)[0], 0);
}

TEST(SimLd58a08, AddressChangeAnswersFromTheOldAddressThenMoves) {
  SimLd58a08 d(1, {});
  EXPECT_EQ(ask(d, "01 06 00 FD 00 02 99 FB"), "01 06 00 FD 00 02 99 FB");
  EXPECT_EQ(d.address(), 2);
  EXPECT_FALSE(d.answersTo(1, nullptr));
  EXPECT_EQ(ask(d, "FF 03 00 FD 00 01 00 24"),
            toHex(encodeReply(Request::readHoldingRegisters(0xFF, 0xFD, 1), {2})));
  const Request to9 = Request::writeSingleRegister(0xFF, 0xFD, 9);
  EXPECT_EQ(ask(d, to9), toHex(encodeRequest(to9)));
  EXPECT_EQ(d.address(), 9);
  // 0xFF reaches only the special registers; the addresses 0 and 249 are refused.
  const Request bits = Request::readCoils(0xFF, 0, 8);
  EXPECT_FALSE(d.answersTo(0xFF, &bits));
  EXPECT_EQ(ask(d, Request::writeSingleRegister(9, 0xFD, 0)),
            exceptionHex(9, kFc06, kIllegalDataValue));
  EXPECT_EQ(ask(d, Request::writeSingleRegister(9, 0xFD, 249)),
            exceptionHex(9, kFc06, kIllegalDataValue));
  EXPECT_EQ(d.address(), 9);
  // 248 (0xF8) is the manual's highest address: taken, and answered there.
  const Request to248 = Request::writeSingleRegister(9, 0xFD, 248);
  EXPECT_EQ(ask(d, to248), toHex(encodeRequest(to248)));
  EXPECT_EQ(d.address(), 248);
  EXPECT_EQ(ask(d, "F8 01 00 00 00 08 29 A5").substr(0, 8), "F8 01 01");
}

TEST(SimLd58a08, BaudAndParityAreStoredAndTakenAtPowerOn) {
  SimLd58a08 d(1, {});
  EXPECT_EQ(ask(d, "01 06 00 FE 00 02 69 FB"), "01 06 00 FE 00 02 69 FB");
  EXPECT_EQ(ask(d, "01 06 00 FF 00 01 78 3A"), "01 06 00 FF 00 01 78 3A");
  EXPECT_EQ(regs(d, 0xFE, 2), (std::vector<uint16_t>{2, 1})) << "read back as stored";
  EXPECT_EQ(d.line().baud, 9600);
  EXPECT_EQ(d.line().parity, Parity::kNone);
  d.powerCycle(SimClock::now());
  EXPECT_EQ(d.line().baud, 4800);
  EXPECT_EQ(d.line().parity, Parity::kEven);
  // Parity over 2 is stored as written and becomes "none" at power-on (manual).
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0xFF, {3}, SimClock::now()), 0);
  EXPECT_EQ(regs(d, 0xFF, 1)[0], 3);
  d.powerCycle(SimClock::now());
  EXPECT_EQ(d.line().parity, Parity::kNone);
  EXPECT_EQ(regs(d, 0xFF, 1)[0], 0);
}

TEST(SimLd58a08, FactoryResetKeepsPlainOutputsAndTheLineUntilPowerOn) {
  for (const char* reset : {"FF 06 00 FB 00 00 ED E5", "01 06 00 FE 00 08 E9 FC"}) {
    SimLd58a08 d(1, {});
    const auto t0 = SimClock::now();
    ASSERT_EQ(d.write(Table::kHoldingRegister, 0xFC, {5, 1, 4, 2}, t0),
              0);  // delay, address, 19200, odd
    ASSERT_EQ(d.write(Table::kHoldingRegister, 0xFA, {1}, t0), 0);
    d.powerCycle(t0);
    ASSERT_EQ(d.line().baud, 19200);
    ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0070, {1000, 50, 0xFFFF}, t0), 0);
    ASSERT_EQ(d.write(Table::kCoil, 0, {1}, t0), 0);
    ASSERT_FALSE(ask(d, reset, t0).empty()) << reset;
    EXPECT_EQ(d.address(), 1) << reset;
    EXPECT_EQ(regs(d, 0xFA, 6, t0), (std::vector<uint16_t>{0, 0, 0, 1, 3, 0})) << reset;
    EXPECT_EQ(regs(d, 0x70, 3, t0), (std::vector<uint16_t>{0, 0, 0})) << reset;
    EXPECT_EQ(regs(d, 0x80, 1, t0)[0], 0x01) << "PWM output off, plain output kept: " << reset;
    EXPECT_EQ(d.line().baud, 19200) << "the line changes at power-on: " << reset;
    d.powerCycle(t0);
    EXPECT_EQ(d.line().baud, 9600) << reset;
    EXPECT_EQ(d.line().parity, Parity::kNone) << reset;
  }
}

TEST(SimLd58a08, PowerDownSaveDecidesWhetherPwmSurvives) {
  SimLd58a08 d(1, {});
  const auto t0 = SimClock::now();
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0020, {100, 50, 0xFFFF}, t0), 0);
  ASSERT_EQ(d.write(Table::kCoil, 7, {1}, t0), 0);
  d.powerCycle(t0 + 1s);
  EXPECT_EQ(regs(d, 0x20, 3, t0 + 1s), (std::vector<uint16_t>{0, 0, 0}));
  EXPECT_EQ(regs(d, 0x80, 1, t0 + 1s)[0], 0) << "outputs off after power-on";
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0xFA, {1}, t0 + 1s), 0);
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0020, {10, 5, 4}, t0 + 1s), 0);  // 4 pulses of 1 s
  EXPECT_EQ(regs(d, 0x22, 1, t0 + 10s)[0], 0) << "the burst ended";
  d.powerCycle(t0 + 20s);
  EXPECT_EQ(regs(d, 0x20, 3, t0 + 20s), (std::vector<uint16_t>{10, 5, 4})) << "as written";
  EXPECT_EQ(coil(d, 2, t0 + 20s + 100ms), 1) << "the saved burst runs again";
  EXPECT_EQ(regs(d, 0x22, 1, t0 + 22s + 500ms)[0], 2);
}

TEST(SimLd58a08, StateRoundTripIsAPowerOnWithThatState) {
  SimLd58a08 d(1, {});
  const auto t0 = SimClock::now();
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0xFA, {1}, t0), 0);
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0xFC, {3, 17, 5, 2}, t0), 0);
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0x0050, {20, 10, 0xFFFF}, t0), 0);
  YAML::Node node;
  d.saveState(node);
  SimLd58a08 e(1, {});
  e.loadState(YAML::Load(YAML::Dump(node)), t0);
  EXPECT_EQ(e.address(), 17);
  EXPECT_EQ(regs(e, 0xFA, 6, t0), (std::vector<uint16_t>{1, 0, 3, 17, 5, 2}));
  EXPECT_EQ(e.line().baud, 9600) << "stored codes wait for a power cycle";
  EXPECT_EQ(regs(e, 0x50, 3, t0), (std::vector<uint16_t>{20, 10, 0xFFFF}));
  EXPECT_EQ(coil(e, 5, t0 + 50ms), 1);
  e.powerCycle(t0);
  EXPECT_EQ(e.line().baud, 38400);
  EXPECT_EQ(e.line().parity, Parity::kOdd);
}
