// Device models against a scripted transport, with the manuals' own frames.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "device_fixtures.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/devices/ld58a08.h"
#include "modbus_rtu_driver/devices/output_batch.h"
#include "modbus_rtu_driver/devices/registry.h"
#include "modbus_rtu_driver/devices/yespeed_pdu.h"

using namespace modbus_rtu_driver;
using namespace modbus_rtu_driver::devtest;

namespace {

// Before an output write the LD58A08 reads the channel's PWM registers: here stopped.
void expectPwmOff(ScriptedTransport& bus, uint8_t ch) {
  const Request read = Request::readHoldingRegisters(1, static_cast<uint16_t>(ch * 0x10), 3);
  bus.expect(toHex(encodeRequest(read)), toHex(encodeReply(read, {0, 0, 0})));
}

}  // namespace

TEST(Ld58a08, SlowPwmIsTheManualsFc16Frame) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  bus.expectEcho("01 10 00 00 00 03 06 01 F4 00 C8 FF FF D6 CA");
  PwmSettings s;
  s.channel = 0;
  s.period = 50.0;
  s.on_time = 20.0;
  s.pulses = 0;  // continuous
  const Result r = board.setPwm(bus, s);
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_SCRIPT_DONE(bus);
}

TEST(Ld58a08, FastPwmIsTheManualsFc16Frame) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  bus.expectEcho("01 10 00 60 00 03 06 27 10 00 1E 03 E8 42 92");
  PwmSettings s;
  s.channel = 6;
  s.frequency = 10000;
  s.duty_cycle = 30;
  s.duration = 100.0;
  EXPECT_TRUE(board.setPwm(bus, s).ok());
  EXPECT_SCRIPT_DONE(bus);
}

TEST(Ld58a08, OutputsUseFc05ForOneAndFc15ForSeveral) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  bus.expect("01 03 00 50 00 03 05 DA", "01 03 06 00 00 00 00 00 00 21 75");  // PWM 5 off
  bus.expect("01 05 00 05 FF 00 9C 3B", "01 05 00 05 FF 00 9C 3B");
  EXPECT_TRUE(OutputBatch::write(board, bus, {5}, {true}).ok());
  // All eight at once: the manual's "channels 0,3,7 ON, others OFF".
  for (uint8_t ch = 0; ch < 8; ++ch) expectPwmOff(bus, ch);
  bus.expect("01 0F 00 00 00 08 01 89 3F 33", "01 0F 00 00 00 08 54 0D");
  EXPECT_TRUE(OutputBatch::write(board, bus, {0, 1, 2, 3, 4, 5, 6, 7},
                                 {true, false, false, true, false, false, false, true})
                  .ok());
  EXPECT_EQ(board.outputs(), (std::vector<bool>{1, 0, 0, 1, 0, 0, 0, 1}));
  EXPECT_SCRIPT_DONE(bus);
}

TEST(Ld58a08, ChannelsWithGapsAreWrittenAloneSoOthersAreNotTouched) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  // Set 0 on and 3 off: one FC05 each, channels 1-2 are not written (nor read).
  expectPwmOff(bus, 0);
  expectPwmOff(bus, 3);
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleCoil(1, 0, true))));
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleCoil(1, 3, false))));
  EXPECT_TRUE(OutputBatch::write(board, bus, {0, 3}, {true, false}).ok());
  EXPECT_TRUE(board.outputs().empty()) << "the others are not known until a poll";
  EXPECT_SCRIPT_DONE(bus);
}

TEST(Ld58a08, PollDecodesOutputsAndPwm) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  // The manual's frames: outputs 2-6 on (01 01 01 7C 50 69).
  expectFirstLd58a08Poll(bus, 0x7C, [](uint16_t ch) {
    return ch == 0   ? std::vector<uint16_t>{500, 200, 0xFFFF}
           : ch == 6 ? std::vector<uint16_t>{10000, 30, 1000}
                     : std::vector<uint16_t>{0, 0, 0};
  });
  ASSERT_TRUE(board.poll(bus).ok());
  EXPECT_EQ(board.outputs(), (std::vector<bool>{0, 0, 1, 1, 1, 1, 1, 0}));
  ASSERT_TRUE(board.pwmKnown());
  EXPECT_DOUBLE_EQ(board.pwm()[0].period, 50.0);
  EXPECT_DOUBLE_EQ(board.pwm()[0].on_time, 20.0);
  // Continuous (0xFFFF) is said as such, not as 65535 pulses left.
  EXPECT_TRUE(board.pwm()[0].running);
  EXPECT_TRUE(board.pwm()[0].continuous);
  EXPECT_EQ(board.pwm()[0].remaining_pulses, 0);
  EXPECT_TRUE(board.pwm()[6].high_speed);
  EXPECT_DOUBLE_EQ(board.pwm()[6].frequency, 10000);
  EXPECT_TRUE(board.pwm()[6].running);
  EXPECT_FALSE(board.pwm()[6].continuous);
  EXPECT_DOUBLE_EQ(board.pwm()[6].remaining_time, 100.0);
  EXPECT_FALSE(board.pwm()[3].running);
  EXPECT_FALSE(board.pwm()[3].continuous);
  EXPECT_EQ(board.pwm()[3].remaining_pulses, 0);
  // Later polls read one channel's registers, then the outputs (docs/devices/ld58a08.md: a run
  // the registers show ended also ended before the outputs were read).
  const Request ch0 = Request::readHoldingRegisters(1, 0, 3);
  bus.expect(toHex(encodeRequest(ch0)), toHex(encodeReply(ch0, {500, 200, 0})));
  bus.expect("01 01 00 00 00 08 3D CC", "01 01 01 00 51 88");
  ASSERT_TRUE(board.poll(bus).ok());
  EXPECT_FALSE(board.pwm()[0].running);
  EXPECT_FALSE(board.pwm()[0].continuous);
  EXPECT_SCRIPT_DONE(bus);
}

// docs/failsafe.md F31: a read that shows a run ended ends it. A read of every channel that
// fails part way keeps what the channels before the failure showed (stop 58's case
// a_pwm_read_before_a_failed_read_counts).
TEST(Ld58a08, ChannelsReadBeforeAFailedReadAreKept) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  expectFirstLd58a08Poll(bus, 0x00, [](uint16_t ch) {
    return ch == 2 ? std::vector<uint16_t>{5, 1, 0xFFFF} : std::vector<uint16_t>{0, 0, 0};
  });
  ASSERT_TRUE(board.poll(bus).ok());
  ASSERT_TRUE(board.outputSelfTimed(2));
  for (uint16_t ch = 0; ch < 3; ++ch) {  // channels 0-2 answer (2 stopped), 3 stays silent
    const Request read = Request::readHoldingRegisters(1, static_cast<uint16_t>(ch * 0x10), 3);
    bus.expect(toHex(encodeRequest(read)), toHex(encodeReply(read, {0, 0, 0})));
  }
  const Request ch3 = Request::readHoldingRegisters(1, 0x30, 3);
  bus.expect(toHex(encodeRequest(ch3)), "");
  EXPECT_FALSE(board.refreshSelfTimed(bus).ok());
  EXPECT_FALSE(board.outputSelfTimed(2)) << "channel 2 was read stopped before channel 3 failed";
  EXPECT_SCRIPT_DONE(bus);
}

TEST(Ld58a08, ReadBackSaysContinuousAndWhatIsLeftExplicitly) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  expectFirstLd58a08Poll(bus, 0x00, [](uint16_t ch) {
    return ch == 1   ? std::vector<uint16_t>{10, 5, 7}
           : ch == 7 ? std::vector<uint16_t>{2000, 55, 0xFFFF}
                     : std::vector<uint16_t>{10, 5, 0};
  });
  ASSERT_TRUE(board.poll(bus).ok());
  const PwmState& burst = board.pwm()[1];
  EXPECT_TRUE(burst.running);
  EXPECT_FALSE(burst.continuous);
  EXPECT_EQ(burst.remaining_pulses, 7);
  const PwmState& endless = board.pwm()[7];
  EXPECT_TRUE(endless.running);
  EXPECT_TRUE(endless.continuous);
  EXPECT_DOUBLE_EQ(endless.remaining_time, 0.0) << "not 6553.5 s";
  const PwmState& off = board.pwm()[2];
  EXPECT_FALSE(off.running);
  EXPECT_FALSE(off.continuous);
  EXPECT_EQ(off.remaining_pulses, 0);
  EXPECT_SCRIPT_DONE(bus);
}

TEST(Ld58a08, PwmMessagesSayTheRealProblem) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  auto slow = [](uint8_t ch, double period, double on) {
    PwmSettings s;
    s.channel = ch;
    s.period = period;
    s.on_time = on;
    return s;
  };
  auto fast = [](uint8_t ch, double f, double duty, double duration) {
    PwmSettings s;
    s.channel = ch;
    s.frequency = f;
    s.duty_cycle = duty;
    s.duration = duration;
    return s;
  };
  PwmSettings pulses_on_fast = fast(6, 1000, 50, 0);
  pulses_on_fast.pulses = 3;
  PwmSettings duration_on_slow = slow(0, 1.0, 0.5);
  duration_on_slow.duration = 2.0;
  const std::vector<std::pair<PwmSettings, std::string>> cases = {
      {fast(7, 1000, 33.3, 0),
       "duty_cycle: 33.3 % is not a whole percent (0-100 % in steps of 1 %)"},
      {fast(7, 1000.5, 30, 0),
       "frequency: 1000.5 Hz is not a whole number of Hz (1-20000 Hz in steps of 1 Hz)"},
      {slow(2, 1.0, 0.55),
       "on_time: 0.55 s is not a multiple of the 0.1 s step (0-6553.4 s in steps of 0.1 s)"},
      {slow(2, 1.05, 0),
       "period: 1.05 s is not a multiple of the 0.1 s step (0.1-6553.5 s in steps of 0.1 s)"},
      {fast(6, 1000, 50, 0.25),
       "duration: 0.25 s is not a multiple of the 0.1 s step (0.1-6553.4 s in steps of 0.1 s; "
       "0 = run continuously)"},
      {fast(6, 1000, 50, 0.05), "duration: 0.05 s is outside 0.1-6553.4 s (0 = run continuously)"},
      {fast(1, 1000, 50, 0),
       "frequency: channel 1 takes period/on_time/pulses (channels 0-5); "
       "frequency/duty_cycle/duration are for channels 6-7"},
      {duration_on_slow,
       "duration: channel 0 takes period/on_time/pulses (channels 0-5); "
       "frequency/duty_cycle/duration are for channels 6-7"},
      {slow(6, 1.0, 0.5),
       "period: channel 6 takes frequency/duty_cycle/duration (channels 6-7); "
       "period/on_time/pulses are for channels 0-5"},
      {pulses_on_fast,
       "pulses: channel 6 takes frequency/duty_cycle/duration (channels 6-7); "
       "period/on_time/pulses are for channels 0-5"},
      {fast(7, 1000, 101, 0), "duty_cycle: 101 % is outside 0-100 %"},
      {slow(2, 1.0, -1), "on_time: -1 s is outside 0-6553.4 s"},
  };
  for (const auto& [settings, message] : cases) {
    const Result r = board.setPwm(bus, settings);
    EXPECT_EQ(r.error, ErrorKind::kInvalidArgument);
    EXPECT_EQ(r.message, message);
  }
  EXPECT_EQ(bus.executed(), 0);
}

TEST(Ld58a08, BadPwmValuesNameTheFieldAndSendNothing) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  struct Case {
    PwmSettings s;
    std::string words;
  };
  auto slow = [](double period, double on, uint16_t pulses) {
    PwmSettings s;
    s.channel = 2;
    s.period = period;
    s.on_time = on;
    s.pulses = pulses;
    return s;
  };
  auto fast = [](double f, double duty, double duration) {
    PwmSettings s;
    s.channel = 7;
    s.frequency = f;
    s.duty_cycle = duty;
    s.duration = duration;
    return s;
  };
  PwmSettings bad_channel = slow(1, 0.5, 0);
  bad_channel.channel = 8;
  const std::vector<Case> cases = {
      {slow(0.05, 0, 0), "period: 0.05 s is outside 0.1-6553.5 s"},
      {slow(6553.6, 0, 0), "period"},
      {slow(1.05, 0, 0), "period"},
      {slow(1.0, 2.0, 0), "on_time: 2 s is longer than the period"},
      {slow(1.0, -1, 0), "on_time"},
      {slow(1.0, 0.5, 65535), "pulses"},
      {fast(0, 50, 0), "frequency: 0 Hz is outside 1-20000 Hz"},
      {fast(20001, 50, 0), "frequency"},
      {fast(1000, 101, 0), "duty_cycle: 101 % is outside 0-100 %"},
      {fast(1000, 50, 0.05), "duration"},
      {fast(1000, 50, 6553.5), "duration"},
      {bad_channel, "channel: 8 is outside 0-7"},
  };
  for (const auto& c : cases) {
    const Result r = board.setPwm(bus, c.s);
    EXPECT_EQ(r.error, ErrorKind::kInvalidArgument);
    EXPECT_NE(r.message.find(c.words), std::string::npos) << r.message;
  }
  EXPECT_EQ(board.stopPwm(bus, 9).error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(board.setReturnDelay(bus, 26).error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(OutputBatch::write(board, bus, {8}, {true}).error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(OutputBatch::write(board, bus, {1, 1}, {true, true}).error,
            ErrorKind::kInvalidArgument);
  EXPECT_EQ(OutputBatch::write(board, bus, {1, 2}, {true}).error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(bus.executed(), 0);
  EXPECT_SCRIPT_DONE(bus);
}

TEST(Ld58a08, StopAndReturnDelayFrames) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleRegister(1, 0x0062, 0))));
  EXPECT_TRUE(board.stopPwm(bus, 6).ok());
  bus.expect("01 06 00 FC 00 05 89 F9", "01 06 00 FC 00 05 89 F9");
  EXPECT_TRUE(board.setReturnDelay(bus, 5).ok());
  EXPECT_SCRIPT_DONE(bus);
}

// The settings the commissioning tool changes, as the device class writes them: one FC06 to
// the manual's register, refused unsent outside its range; the factory reset as the manual
// prints it (through 0xFF).
TEST(Ld58a08, SettingsFramesAndRanges) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  bus.expect("01 03 00 FE 00 01 E5 FA", "01 03 02 00 03 F8 45");
  uint16_t code = 0;
  ASSERT_TRUE(board.readSetting(bus, Ld58a08Setting::kBaud, &code).ok());
  EXPECT_EQ(code, 3);
  const std::pair<Ld58a08Setting, uint16_t> writes[] = {{Ld58a08Setting::kPowerDownSave, 1},
                                                        {Ld58a08Setting::kAddress, 248},
                                                        {Ld58a08Setting::kBaud, 7},
                                                        {Ld58a08Setting::kParity, 2}};
  for (const auto& w : writes) {
    const Request request =
        Request::writeSingleRegister(1, static_cast<uint16_t>(w.first), w.second);
    bus.expectEcho(toHex(encodeRequest(request)));
    EXPECT_TRUE(board.writeSetting(bus, w.first, w.second).ok());
  }
  EXPECT_SCRIPT_DONE(bus);
  const std::pair<Ld58a08Setting, uint16_t> refused[] = {
      {Ld58a08Setting::kPowerDownSave, 2}, {Ld58a08Setting::kReturnDelay, 26},
      {Ld58a08Setting::kAddress, 0},       {Ld58a08Setting::kAddress, 249},
      {Ld58a08Setting::kBaud, 8},          {Ld58a08Setting::kParity, 3}};
  for (const auto& w : refused)
    EXPECT_EQ(board.writeSetting(bus, w.first, w.second).error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(bus.executed(), 5);
  EXPECT_EQ(Ld58a08::validateSetting(Ld58a08Setting::kBaud, 8),
            "baud_code: 8 is outside 0-7 (1200-115200; the board takes a higher code as a "
            "factory reset)");
  EXPECT_EQ(Ld58a08::validateSetting(Ld58a08Setting::kAddress, 249),
            "address: 249 is outside 1-248");
  Ld58a08 every_board(config("ld58a08", 0xFF));
  ScriptedTransport reset_bus;
  reset_bus.expect("FF 06 00 FB 00 00 ED E5", "FF 06 00 FB 00 00 ED E5");
  EXPECT_TRUE(every_board.factoryReset(reset_bus).ok());
  EXPECT_SCRIPT_DONE(reset_bus);
}

TEST(Ld58a08, ADeviceThatDoesNotConfirmIsNotSuccess) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  expectPwmOff(bus, 0);
  bus.expect("01 05 00 00 FF 00 8C 3A");                          // silence
  bus.expect(toHex(encodeRequest(Request::readCoils(1, 0, 8))));  // and to the read-back
  const Result silent = OutputBatch::write(board, bus, {0}, {true});
  EXPECT_EQ(silent.error, ErrorKind::kTimeout);
  EXPECT_NE(silent.message.find("not confirmed"), std::string::npos) << silent.message;
  expectPwmOff(bus, 0);
  bus.expect("01 05 00 00 FF 00 8C 3A", toHex(encodeException(1, 5, 4)));
  const Result r = OutputBatch::write(board, bus, {0}, {true});
  EXPECT_EQ(r.error, ErrorKind::kException);
  EXPECT_NE(r.message.find("slave device failure"), std::string::npos);
  EXPECT_SCRIPT_DONE(bus);
}

// Manual, 0x0080: the outputs apply only with the channel's PWM enable register at 0. An output
// write to a channel whose PWM runs stops the PWM first (FC06 0 to 0x00n2), then writes.
TEST(Ld58a08, AnOutputOnARunningPwmChannelStopsThePwmFirst) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  bus.expect("01 03 00 30 00 03 05 C4", "01 03 06 00 0A 00 05 FF FF A8 C5");  // 1 s, 0.5 s, run
  bus.expect("01 06 00 32 00 00 28 05", "01 06 00 32 00 00 28 05");           // enable 0
  bus.expect("01 05 00 03 FF 00 7C 3A", "01 05 00 03 FF 00 7C 3A");           // DO 3 on
  const Result r = OutputBatch::write(board, bus, {3}, {true});
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.message, "PWM on channel 3 stopped first");
  EXPECT_FALSE(board.pwm()[3].running);
  EXPECT_SCRIPT_DONE(bus);
  // A fast channel, switched off: its output time register is the enable register.
  bus.expect("01 03 00 70 00 03 04 10", "01 03 06 07 D0 00 37 FF FF 51 6E");
  bus.expect("01 06 00 72 00 00 29 D1", "01 06 00 72 00 00 29 D1");
  bus.expect("01 05 00 07 00 00 7C 0B", "01 05 00 07 00 00 7C 0B");
  const Result off = OutputBatch::write(board, bus, {7}, {false});
  EXPECT_TRUE(off.ok()) << off.message;
  EXPECT_EQ(off.message, "PWM on channel 7 stopped first");
  EXPECT_SCRIPT_DONE(bus);
}

TEST(Ld58a08, SeveralOutputsStopOnlyTheChannelsThatRun) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  bus.expect("01 03 00 20 00 03 04 01", "01 03 06 00 0A 00 05 00 00 A9 75");  // 2: stopped
  bus.expect("01 03 00 30 00 03 05 C4", "01 03 06 00 0A 00 05 FF FF A8 C5");  // 3: runs
  bus.expect("01 06 00 32 00 00 28 05", "01 06 00 32 00 00 28 05");
  bus.expect("01 0F 00 02 00 02 01 03 E7 56", "01 0F 00 02 00 02 75 CA");  // DO 2, 3 on
  const Result r = OutputBatch::write(board, bus, {2, 3}, {true, true});
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.message, "PWM on channel 3 stopped first");
  EXPECT_SCRIPT_DONE(bus);
}

TEST(Ld58a08, ALostStopReplyIsReadBackBeforeTheOutputIsWritten) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  bus.expect("01 03 00 30 00 03 05 C4", "01 03 06 00 0A 00 05 FF FF A8 C5");
  bus.expect("01 06 00 32 00 00 28 05");                                      // reply lost
  bus.expect("01 03 00 30 00 03 05 C4", "01 03 06 00 0A 00 05 00 00 A9 75");  // stopped
  bus.expect("01 05 00 03 FF 00 7C 3A");                                      // reply lost
  bus.expect("01 01 00 00 00 08 3D CC", "01 01 01 08 50 4E");                 // DO 3 on
  const Result r = OutputBatch::write(board, bus, {3}, {true});
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.message.rfind("PWM on channel 3 stopped first; confirmed by reading the outputs", 0),
            0u)
      << r.message;
  EXPECT_SCRIPT_DONE(bus);
}

TEST(Ld58a08, APwmThatCouldNotBeStoppedLeavesTheOutputUnwritten) {
  Ld58a08 board(config("ld58a08", 1));
  ScriptedTransport bus;
  bus.expect("01 03 00 30 00 03 05 C4", "01 03 06 00 0A 00 05 FF FF A8 C5");
  bus.expect("01 06 00 32 00 00 28 05");                                      // reply lost
  bus.expect("01 03 00 30 00 03 05 C4", "01 03 06 00 0A 00 05 FF FF A8 C5");  // still runs
  const Result r = OutputBatch::write(board, bus, {3}, {true});
  EXPECT_EQ(r.error, ErrorKind::kTimeout);
  EXPECT_NE(r.message.find("PWM runs on channel 3 and stopping it failed"), std::string::npos)
      << r.message;
  EXPECT_NE(r.message.find("not done (channel 3 still runs)"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("outputs not written"), std::string::npos) << r.message;
  EXPECT_SCRIPT_DONE(bus);  // no FC05
  // An unreadable PWM state: nothing written either.
  bus.expect("01 03 00 30 00 03 05 C4");
  const Result unknown = OutputBatch::write(board, bus, {3}, {true});
  EXPECT_FALSE(unknown.ok());
  EXPECT_NE(unknown.message.find("outputs not written: whether PWM runs on channel 3 is unknown"),
            std::string::npos)
      << unknown.message;
  EXPECT_SCRIPT_DONE(bus);
}

TEST(LcRelay8, ManualFramesAtAddress255) {
  LcRelay8 board(config("lc_relay8", 255));
  ScriptedTransport bus;
  bus.expect("FF 05 00 00 FF 00 99 E4", "FF 05 00 00 FF 00 99 E4");
  EXPECT_TRUE(OutputBatch::write(board, bus, {0}, {true}).ok());
  bus.expect("FF 0F 00 00 00 08 01 FF 30 1D", "FF 0F 00 00 00 08 41 D3");
  EXPECT_TRUE(
      OutputBatch::write(board, bus, {0, 1, 2, 3, 4, 5, 6, 7}, std::vector<bool>(8, true)).ok());
  bus.expect("FF 01 00 00 00 08 28 12", "FF 01 01 01 A1 A0");
  bus.expect("FF 02 00 00 00 08 6C 12", "FF 02 01 01 51 A0");
  ASSERT_TRUE(board.poll(bus).ok());
  EXPECT_EQ(board.outputs(), (std::vector<bool>{1, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(board.inputs(), (std::vector<bool>{1, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_SCRIPT_DONE(bus);
}

TEST(LcRelay8, FlashCloseAndFlashOpen) {
  LcRelay8 board(config("lc_relay8", 255));
  ScriptedTransport bus;
  bus.expect("FF 10 00 03 00 02 04 00 04 00 14 C5 9F", "FF 10 00 03 00 02 A4 16");
  EXPECT_TRUE(board.pulse(bus, 0, true, 2.0).ok());
  bus.expect("FF 10 00 03 00 02 04 00 02 00 1E A5 99", "FF 10 00 03 00 02 A4 16");
  EXPECT_TRUE(board.pulse(bus, 0, false, 3.0).ok());
  // Relay #8 lives at 0x0026.
  const Request r8 = Request::writeMultipleRegisters(255, 0x0026, {4, 1});
  bus.expectEcho(toHex(encodeRequest(r8)));
  EXPECT_TRUE(board.pulse(bus, 7, true, 0.1).ok());
  EXPECT_NE(LcRelay8::validatePulse(0, 0.0).find("duration"), std::string::npos);
  EXPECT_NE(LcRelay8::validatePulse(0, 6553.6).find("duration"), std::string::npos);
  EXPECT_NE(LcRelay8::validatePulse(0, 1.25).find("steps of 0.1 s"), std::string::npos);
  EXPECT_NE(LcRelay8::validatePulse(8, 1.0).find("channel"), std::string::npos);
  EXPECT_EQ(board.pulse(bus, 8, true, 1.0).error, ErrorKind::kInvalidArgument);
  EXPECT_SCRIPT_DONE(bus);
}

TEST(LcRelay8, AddressAndBaudCommands) {
  LcRelay8 board(config("lc_relay8", 255));
  ScriptedTransport bus;
  bus.expect("00 03 00 00 00 01 85 DB", "00 03 02 00 FF C5 C4");
  Result r = LcRelay8::readAddressAtZero(bus);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, std::vector<uint16_t>{255});
  bus.expect("00 10 00 00 00 01 02 00 FF EB 80", "00 10 00 00 00 01 02 00 FF EB 80");
  r = LcRelay8::setAddressAtZero(bus, 255);
  EXPECT_TRUE(r.ok()) << r.message;
  bus.expect("FF 10 03 E9 00 01 02 00 03 8B CC", "FF 10 03 E9 00 01 C5 A7");
  EXPECT_TRUE(board.writeBaudCode(bus, 3).ok());
  bus.expect("FF 03 03 E8 00 01 11 A4", "FF 03 02 00 04 90 53");
  uint16_t code = 0;
  EXPECT_TRUE(board.readBaudCode(bus, &code).ok());
  EXPECT_EQ(code, 4);
  EXPECT_EQ(board.writeBaudCode(bus, 5).error, ErrorKind::kInvalidArgument);
  EXPECT_SCRIPT_DONE(bus);
}

TEST(YespeedPdu, TelemetryInOneRequestAsTheManualReadsIt) {
  YespeedPdu pdu(config("yespeed_pdu", 1));
  ScriptedTransport bus;
  bus.expect("01 01 00 00 00 08 3D CC", "01 01 01 01 90 48");
  bus.expect("01 04 00 00 00 05 30 09", "01 04 0A 00 DD 02 71 08 98 02 D5 06 3B 86 51");
  bus.expect("01 03 00 00 00 03 05 CB", "01 03 06 09 C4 07 D0 06 40 D2 E0");
  ASSERT_TRUE(pdu.poll(bus).ok());
  EXPECT_TRUE(pdu.readingFresh());
  EXPECT_NEAR(pdu.reading().temperature, 22.1, 1e-9);
  EXPECT_NEAR(pdu.reading().humidity, 62.5, 1e-9);
  EXPECT_NEAR(pdu.reading().voltage, 220.0, 1e-9);
  EXPECT_NEAR(pdu.reading().current, 7.25, 1e-9);
  EXPECT_NEAR(pdu.reading().power, 1595, 1e-9);
  ASSERT_TRUE(pdu.limitsKnown());
  EXPECT_NEAR(pdu.limits().over_voltage, 250.0, 1e-9);
  EXPECT_NEAR(pdu.limits().under_voltage, 200.0, 1e-9);
  EXPECT_NEAR(pdu.limits().over_current, 16.0, 1e-9);
  EXPECT_EQ(pdu.outputs()[0], true);
  // Negative temperatures are signed; a failed read leaves nothing fresh to publish.
  bus.expect("01 01 00 00 00 08 3D CC", "01 01 01 00 51 88");
  const Request t = Request::readInputRegisters(1, 0, 5);
  bus.expect(toHex(encodeRequest(t)), toHex(encodeReply(t, {0xFFC9, 300, 2203, 730, 1581})));
  ASSERT_TRUE(pdu.poll(bus).ok());
  EXPECT_NEAR(pdu.reading().temperature, -5.5, 1e-9);
  bus.expect("01 01 00 00 00 08 3D CC", "01 01 01 00 51 88");
  bus.expect(toHex(encodeRequest(t)));  // silence
  EXPECT_FALSE(pdu.poll(bus).ok());
  EXPECT_FALSE(pdu.readingFresh());
  // Nor does a poll whose first read (the relays) failed, after a good one: the PDU unplugged
  // went on publishing its last telemetry, newly stamped, every poll (issue #33 item 3's plot
  // of a real bag showed the outage as a flat line).
  bus.expect("01 01 00 00 00 08 3D CC", "01 01 01 00 51 88");
  bus.expect(toHex(encodeRequest(t)), toHex(encodeReply(t, {0xFFC9, 300, 2203, 730, 1581})));
  ASSERT_TRUE(pdu.poll(bus).ok());
  ASSERT_TRUE(pdu.readingFresh());
  bus.expect("01 01 00 00 00 08 3D CC");  // silence
  EXPECT_FALSE(pdu.poll(bus).ok());
  EXPECT_FALSE(pdu.readingFresh());
  EXPECT_SCRIPT_DONE(bus);
}

TEST(YespeedPdu, LimitsAreOneFc16ThenReadBack) {
  YespeedPdu pdu(config("yespeed_pdu", 1));
  ScriptedTransport bus;
  bus.expectEcho("01 10 00 00 00 03 06 0A 28 06 40 02 BC 87 A1");
  const Request back = Request::readHoldingRegisters(1, 0, 3);
  bus.expect(toHex(encodeRequest(back)), toHex(encodeReply(back, {2600, 1600, 700})));
  // float32 values as they arrive from a ROS message
  PduLimitValues l{static_cast<float>(260.0), static_cast<float>(160.0), static_cast<float>(7.0)};
  const Result r = pdu.setLimits(bus, l);
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(pdu.limits().over_current, 7.0, 1e-9);
  EXPECT_SCRIPT_DONE(bus);
}

TEST(YespeedPdu, LimitRulesNameTheField) {
  struct Case {
    PduLimitValues l;
    std::string words;
  };
  const std::vector<Case> cases = {
      {{180.0, 100.0, 10.0}, "over_voltage: 180.0 V (register 1800) must be above 180.0 V"},
      {{250.0, 280.0, 10.0}, "under_voltage: 280.0 V (register 2800) must be below 280.0 V"},
      {{200.0, 210.0, 10.0}, "over_voltage: 200.0 V must be above under_voltage (210.0 V)"},
      {{250.0, 200.0, 5.0},
       "over_current: 5.00 A (register 500) must be between 5.00 A and 20.00 A"},
      {{250.0, 200.0, 20.0}, "over_current"},
      {{250.05, 200.0, 10.0}, "over_voltage: 250.05 V is outside 0-6553.5 V in steps of 0.1 V"},
      {{250.0, 200.0, 10.001}, "over_current"},
      {{-1.0, 200.0, 10.0}, "over_voltage"},
  };
  for (const auto& c : cases) {
    const std::string e = YespeedPdu::validateLimits(c.l);
    EXPECT_NE(e.find(c.words), std::string::npos) << "got: " << e;
  }
  EXPECT_EQ(YespeedPdu::validateLimits({260.0, 160.0, 7.0}), "");
  EXPECT_EQ(YespeedPdu::validateLimits({180.1, 100.0, 19.99}), "");
  YespeedPdu pdu(config("yespeed_pdu", 1));
  ScriptedTransport bus;
  EXPECT_EQ(pdu.setLimits(bus, {170.0, 160.0, 10.0}).error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(bus.executed(), 0);
}

// Issue #13/6: the rules hold for the integer that is written, not for the double asked for.
// 180.00001 V is written as 1800 and 19.999999 A as 2000, both of which the PDU refuses.
TEST(YespeedPdu, LimitRulesAreCheckedOnTheRegisterValuesWritten) {
  EXPECT_NE(YespeedPdu::validateLimits({180.00001, 100.0, 10.0})
                .find("over_voltage: 180.0 V (register 1800) must be above 180.0 V"),
            std::string::npos);
  EXPECT_NE(YespeedPdu::validateLimits({250.0, 200.0, 19.999999})
                .find("over_current: 20.00 A (register 2000) must be between"),
            std::string::npos);
  EXPECT_NE(YespeedPdu::validateLimits({250.0, 280.000001, 10.0})
                .find("under_voltage: 280.0 V (register 2800)"),
            std::string::npos);
  EXPECT_NE(YespeedPdu::validateLimits({250.0, 200.0, 5.0000001}).find("register 500"),
            std::string::npos);
  // over > under on the registers: 200.00001 V and 200.0 V are both 2000.
  EXPECT_NE(YespeedPdu::validateLimits({200.00001, 200.0, 10.0})
                .find("over_voltage: 200.0 V must be above under_voltage (200.0 V)"),
            std::string::npos);
  YespeedPdu pdu(config("yespeed_pdu", 1));
  ScriptedTransport bus;
  EXPECT_EQ(pdu.setLimits(bus, {180.00001, 100.0, 10.0}).error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(pdu.setLimits(bus, {250.0, 200.0, 19.999999}).error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(bus.executed(), 0);  // nothing reached the bus
  // Float noise below the rule's edge is still the next step: 180.1 V as float32 is 1801.
  PduLimitRegisters regs{};
  EXPECT_EQ(YespeedPdu::validateLimits({static_cast<float>(180.1), 100.0, 19.99}, &regs), "");
  EXPECT_EQ(regs, (PduLimitRegisters{1801, 1000, 1999}));
}

// One limit alone: the others are read from the device, the rules checked on the merged set,
// then all three written in one FC16 and read back.
TEST(YespeedPdu, OneLimitAloneKeepsTheOthersTheDeviceHolds) {
  YespeedPdu pdu(config("yespeed_pdu", 1));
  ScriptedTransport bus;
  bus.expect("01 03 00 00 00 03 05 CB", "01 03 06 09 C4 07 D0 06 40 D2 E0");  // 250, 200, 16
  const Request all = Request::writeMultipleRegisters(1, 0, {2600, 2000, 1600});
  bus.expectEcho(toHex(encodeRequest(all)));
  const Request back = Request::readHoldingRegisters(1, 0, 3);
  bus.expect(toHex(encodeRequest(back)), toHex(encodeReply(back, {2600, 2000, 1600})));
  PduLimitChange change;
  change[0] = 2600;
  const Result r = pdu.changeLimits(bus, change);
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(pdu.limits().over_voltage, 260.0, 1e-9);
  EXPECT_SCRIPT_DONE(bus);

  // The merged set breaks a rule: read, nothing written.
  bus.expect("01 03 00 00 00 03 05 CB", "01 03 06 09 C4 07 D0 06 40 D2 E0");
  change = {};
  change[0] = 1900;  // not above the device's under-voltage 200.0 V
  const Result refused = pdu.changeLimits(bus, change);
  EXPECT_EQ(refused.error, ErrorKind::kInvalidArgument);
  EXPECT_NE(refused.message.find("over_voltage: 190.0 V must be above under_voltage (200.0 V)"),
            std::string::npos)
      << refused.message;
  EXPECT_NE(refused.message.find("nothing was written"), std::string::npos);
  EXPECT_SCRIPT_DONE(bus);

  // A read back that differs from what was written is not reported as success.
  bus.expectEcho("01 10 00 00 00 03 06 0A 28 06 40 02 BC 87 A1");
  bus.expect(toHex(encodeRequest(back)), toHex(encodeReply(back, {2500, 2000, 1600})));
  const Result ignored = pdu.setLimits(bus, {260.0, 160.0, 7.0});
  EXPECT_FALSE(ignored.ok());
  EXPECT_NE(ignored.message.find("holds 250.0 V / 200.0 V / 16.00 A"), std::string::npos)
      << ignored.message;
  EXPECT_SCRIPT_DONE(bus);
}

TEST(LcRelay8, FlashTimeIsCheckedOnTheTenthsWritten) {
  LcRelay8 board(config("lc_relay8", 255));
  ScriptedTransport bus;
  // 0.09999999 s is written as 1 (0.1 s) and 6553.5000001 s as 0xFFFF: both valid.
  const Request shortest = Request::writeMultipleRegisters(255, 0x0003, {4, 1});
  bus.expectEcho(toHex(encodeRequest(shortest)));
  EXPECT_TRUE(board.pulse(bus, 0, true, 0.09999999).ok());
  const Request longest = Request::writeMultipleRegisters(255, 0x0003, {4, 0xFFFF});
  bus.expectEcho(toHex(encodeRequest(longest)));
  EXPECT_TRUE(board.pulse(bus, 0, true, 6553.5000001).ok());
  // 0.04 s would be 0 tenths, 6553.55 s is not a whole step: refused, nothing sent.
  EXPECT_NE(LcRelay8::validatePulse(0, 0.04).find("duration"), std::string::npos);
  EXPECT_NE(LcRelay8::validatePulse(0, 6553.55).find("duration"), std::string::npos);
  EXPECT_NE(LcRelay8::validatePulse(0, std::nan("")).find("duration"), std::string::npos);
  EXPECT_SCRIPT_DONE(bus);
}

// Issue #33 item 5: 1.25 s is inside the range; what it breaks is the 0.1 s step, and the
// answer says which rule.
TEST(LcRelay8, APulseOffTheStepIsRefusedForTheStepNotTheRange) {
  EXPECT_EQ(LcRelay8::validatePulse(0, 1.25),
            "duration: 1.25 s is not a multiple of the 0.1 s step (0.1-6553.5 s in steps of "
            "0.1 s)");
  EXPECT_EQ(LcRelay8::validatePulse(0, 0.04), "duration: 0.04 s is outside 0.1-6553.5 s");
  EXPECT_EQ(LcRelay8::validatePulse(0, 6600), "duration: 6600 s is outside 0.1-6553.5 s");
  EXPECT_EQ(LcRelay8::validatePulse(0, -std::nan("")), "duration: nan s is outside 0.1-6553.5 s");
}

TEST(Registry, TypesAddressesAndNames) {
  // Each type's own file registered it (core/config/type_registry.h); listed alphabetically. A new
  // type joins the list without an edit here.
  const std::vector<std::string> names = knownDeviceTypes();
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  for (const char* builtin : {"generic", "lc_relay8", "ld58a08", "yespeed_pdu"})
    EXPECT_NE(std::find(names.begin(), names.end(), builtin), names.end()) << builtin;
  EXPECT_EQ(validateDeviceConfig(config("lc_relay8", 255)), "");
  EXPECT_EQ(validateDeviceConfig(config("ld58a08", 249)),
            "devices/dev/address: 249 is outside 1-248 for ld58a08");
  EXPECT_EQ(validateDeviceConfig(config("ld58a08", 248)), "") << "its manual: 1-248";
  EXPECT_EQ(validateDeviceConfig(config("yespeed_pdu", 248)),
            "devices/dev/address: 248 is outside 1-247 for yespeed_pdu");
  EXPECT_NE(validateDeviceConfig(config("relay", 3)).find("devices/dev/type: 'relay'"),
            std::string::npos);
  EXPECT_EQ(createDevice(config("relay", 3)), nullptr);
  // Every registered type builds from its config, as the class of the descriptor it registered
  // with (its name and channel counts come from there; generic: no channels of its own, its
  // signals come from the YAML).
  for (const DeviceDescriptor* type : deviceClasses().types()) {
    const std::unique_ptr<Device> made = createDevice(config(type->name, 1));
    ASSERT_NE(made, nullptr) << type->name;
    EXPECT_EQ(&made->descriptor(), type) << type->name;
  }
  DeviceConfig c = config("yespeed_pdu", 3);
  c.inputs = {"a", "b", "c", "d", "e", "f", "g", "h"};
  EXPECT_NE(validateDeviceConfig(c).find("has no inputs"), std::string::npos);
  c = config("ld58a08", 3);
  EXPECT_EQ(createDevice(c)->outputNames()[7], "out7");
}
