// The bus core against the simulator over a real pty: every function code, address 255,
// address-0 operations, each exception, a timeout, a CRC error, reply delay, power cycle.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>

#include "modbus_rtu_driver/core/link/rtu_link.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/devices/ld58a08.h"
#include "modbus_rtu_driver/devices/output_batch.h"
#include "modbus_rtu_driver/devices/registry.h"
#include "modbus_rtu_driver/sim/simulator.h"

using namespace modbus_rtu_driver;

namespace {

class LinkVsSimulator : public ::testing::Test {
 protected:
  void SetUp() override {
    SimulatorConfig config;
    config.devices = {{"lc_relay8", 255}, {"ld58a08", 1}, {"yespeed_pdu", 2}};
    SimulatorOptions options;
    options.link = "/tmp/modbus_rtu_gtest_" + std::to_string(getpid()) + "/tty";
    sim_ = std::make_unique<Simulator>(config, options);
    std::string error;
    ASSERT_TRUE(sim_->start(&error)) << error;
    link_ = makeLink(9600);
  }
  std::unique_ptr<RtuLink> makeLink(int baud, double min_gap = 0) {
    LinkConfig c;
    c.port = sim_->link();
    c.baud = baud;
    c.min_gap = min_gap;
    c.response_timeout = 0.15;
    c.retries = 0;
    auto link = std::make_unique<RtuLink>(c);
    std::string error;
    EXPECT_TRUE(link->connect(&error)) << error;
    return link;
  }
  std::string sim(const std::string& command) { return sim_->command(command); }

  std::unique_ptr<Simulator> sim_;
  std::unique_ptr<RtuLink> link_;
};

}  // namespace

TEST_F(LinkVsSimulator, EveryFunctionCode) {
  Result r = link_->execute(Request::writeSingleCoil(255, 2, true));  // FC05 at 255
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(sim("get 255 coil 0 8"), "ok 0 0 1 0 0 0 0 0");
  r = link_->execute(Request::writeMultipleCoils(255, 4, {true, true}));  // FC15
  ASSERT_TRUE(r.ok()) << r.message;
  r = link_->execute(Request::readCoils(255, 0, 8));  // FC01
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, (std::vector<uint16_t>{0, 0, 1, 0, 1, 1, 0, 0}));
  EXPECT_EQ(sim("set 255 discrete_input 6 1"), "ok");
  r = link_->execute(Request::readDiscreteInputs(255, 0, 8));  // FC02
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values[6], 1);
  r = link_->execute(Request::writeSingleRegister(1, 0x0080, 0x0009));  // FC06
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(sim("get 1 coil 0 8"), "ok 1 0 0 1 0 0 0 0");
  r = link_->execute(Request::readHoldingRegisters(1, 0x00FD, 1));  // FC03
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, std::vector<uint16_t>{1});
  r = link_->execute(Request::writeMultipleRegisters(2, 0, {2600, 1600, 700}));  // FC16
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(sim("get 2 holding_register 0 3"), "ok 2600 1600 700");
  EXPECT_EQ(sim("set 2 input_register 2 2203"), "ok");
  r = link_->execute(Request::readInputRegisters(2, 0, 5));  // FC04
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values[2], 2203);
}

TEST_F(LinkVsSimulator, AddressZeroOperationsOfTheLcBoard) {
  Result r = LcRelay8::readAddressAtZero(*link_);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, std::vector<uint16_t>{255});
  r = LcRelay8::setAddressAtZero(*link_, 200);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_TRUE(link_->execute(Request::readCoils(200, 0, 8)).ok());
  EXPECT_EQ(link_->execute(Request::readCoils(255, 0, 8)).error, ErrorKind::kTimeout);
}

TEST_F(LinkVsSimulator, BroadcastReachesEveryDeviceAndNobodyAnswers) {
  const Result r = link_->execute(Request::writeSingleCoil(0, 0, true));
  ASSERT_TRUE(r.ok()) << r.message;
  // The next transaction's gap gives the simulator time to apply it.
  ASSERT_TRUE(link_->execute(Request::readCoils(1, 0, 1)).ok());
  EXPECT_EQ(sim("get 255 coil 0"), "ok 1");
  EXPECT_EQ(sim("get 1 coil 0"), "ok 1");
  EXPECT_EQ(sim("get 2 coil 0"), "ok 1");
  EXPECT_EQ(link_->stats().broadcasts, 1u);
}

TEST_F(LinkVsSimulator, EachException) {
  Result r = link_->execute(Request::readDiscreteInputs(1, 0, 8));  // LD58A08 has no FC02
  EXPECT_EQ(r.exception_code, kIllegalFunction) << r.message;
  r = link_->execute(Request::readHoldingRegisters(255, 0x0100, 1));
  EXPECT_EQ(r.exception_code, kIllegalDataAddress) << r.message;
  r = link_->execute(Request::writeSingleRegister(2, 0, 1700));  // over-voltage must be > 180 V
  EXPECT_EQ(r.exception_code, kIllegalDataValue) << r.message;
  EXPECT_EQ(sim("fail 2 1"), "ok");
  r = link_->execute(Request::readInputRegisters(2, 0, 5));
  EXPECT_EQ(r.exception_code, kSlaveDeviceFailure) << r.message;
  EXPECT_NE(r.message.find("slave device failure"), std::string::npos);
  EXPECT_EQ(link_->stats().exceptions, 4u);
}

TEST_F(LinkVsSimulator, TimeoutAndCrcError) {
  EXPECT_EQ(link_->execute(Request::readCoils(77, 0, 8)).error, ErrorKind::kTimeout);
  EXPECT_EQ(sim("corrupt 1 1"), "ok");
  EXPECT_EQ(link_->execute(Request::readCoils(1, 0, 8)).error, ErrorKind::kCrc);
  EXPECT_EQ(sim("corrupt 255 1"), "ok");
  EXPECT_EQ(link_->execute(Request::readCoils(255, 0, 8)).error, ErrorKind::kCrc);
  EXPECT_TRUE(link_->execute(Request::readCoils(255, 0, 8)).ok());
  EXPECT_EQ(sim("silence 1 1"), "ok");
  EXPECT_EQ(link_->execute(Request::readCoils(1, 0, 8)).error, ErrorKind::kTimeout);
  const LinkStats s = link_->stats();
  EXPECT_EQ(s.timeouts, 2u);
  EXPECT_EQ(s.crc_errors, 2u);
}

TEST_F(LinkVsSimulator, ReplyDelayIsCoveredByTheResponseTimeout) {
  // LD58A08 return delay 25 x 40 ms = 1 s, far beyond the link's 150 ms timeout: a machine
  // busy enough to start the wait late still sees the timeout (5 x 40 ms once did not).
  ASSERT_TRUE(link_->execute(Request::writeSingleRegister(1, 0x00FC, 25)).ok());
  EXPECT_EQ(link_->execute(Request::readCoils(1, 0, 8)).error, ErrorKind::kTimeout);
  link_->setReplyDelay(1, 1.0);
  const Result r = link_->execute(Request::readCoils(1, 0, 8));
  EXPECT_TRUE(r.ok()) << r.message;
}

TEST_F(LinkVsSimulator, BaudChangeTakesEffectAfterPowerCycle) {
  ASSERT_TRUE(link_->execute(Request::writeSingleRegister(1, 0x00FE, 4)).ok());  // 19200
  EXPECT_TRUE(link_->execute(Request::readCoils(1, 0, 8)).ok());  // still 9600 until power-on
  EXPECT_EQ(sim("power_cycle"), "ok");
  EXPECT_EQ(link_->execute(Request::readCoils(1, 0, 8)).error, ErrorKind::kTimeout);
  link_->disconnect();
  auto fast = makeLink(19200);
  const Result r = fast->execute(Request::readCoils(1, 0, 8));
  EXPECT_TRUE(r.ok()) << r.message;
  // The other devices stayed at 9600.
  EXPECT_EQ(fast->execute(Request::readCoils(2, 0, 8)).error, ErrorKind::kTimeout);
}

TEST_F(LinkVsSimulator, Ld58a08AnswersAt0xFFAndChangesAddress) {
  EXPECT_EQ(sim("silence 255 1"), "ok");  // 0xFF commands need the board alone on the bus
  Result r = link_->execute(Request::readHoldingRegisters(0xFF, 0x00FD, 1));
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, std::vector<uint16_t>{1});
  ASSERT_TRUE(link_->execute(Request::writeSingleRegister(1, 0x00FD, 9)).ok());
  const Result at9 = link_->execute(Request::readCoils(9, 0, 8));
  EXPECT_TRUE(at9.ok()) << at9.message;
  EXPECT_EQ(link_->execute(Request::readCoils(1, 0, 8)).error, ErrorKind::kTimeout);
}

// The LD58A08 manual allows addresses 1-248. libmodbus 3.1.6 cannot address 248, so the link
// sends and reads those frames itself (as for the LC board at 255): the whole device works there.
TEST_F(LinkVsSimulator, Ld58a08At248WorksEndToEnd) {
  ASSERT_TRUE(link_->execute(Request::writeSingleRegister(1, 0x00FD, 248)).ok());
  DeviceConfig config;
  config.name = "pwm_board";
  config.type = "ld58a08";
  config.address = 248;
  ASSERT_EQ(validateDeviceConfig(config), "");
  std::unique_ptr<Device> device = createDevice(config);
  ASSERT_NE(device, nullptr);
  auto& board = static_cast<Ld58a08&>(*device);
  Result r = board.poll(*link_);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_TRUE(board.pwmKnown());
  r = OutputBatch::write(board, *link_, {3}, {true});
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(sim("get 248 coil 0 8"), "ok 0 0 0 1 0 0 0 0");
  PwmSettings s;
  s.channel = 6;
  s.frequency = 2000;
  s.duty_cycle = 30;
  r = board.setPwm(*link_, s);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(sim("get 248 holding_register 0x60 3"), "ok 2000 30 65535");
  Ld58a08Settings settings;
  r = board.readSettings(*link_, &settings);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(settings.address, 248);
  EXPECT_EQ(link_->execute(Request::readCoils(1, 0, 8)).error, ErrorKind::kTimeout);
}

// A gap shorter than a sleep's own wake-up cost is spun, not slept, at normal priority: with a
// 15 us gap (less than kBriefGap) no request waited in a sleep (one would show late= above zero).
TEST_F(LinkVsSimulator, ABriefGapIsNotSlept) {
  link_.reset();  // one link on the pty at a time
  link_ = makeLink(9600, 15e-6);
  std::vector<double> late;
  link_->setWireObserver([&](const WireEvent& e) {
    if (e.outgoing) late.push_back(e.gap_late);
  });
  for (int i = 0; i < 200; ++i) {
    const Result r = link_->execute(Request::readCoils(255, 0, 8));
    ASSERT_TRUE(r.ok()) << r.message;
  }
  ASSERT_EQ(late.size(), 200u);
  EXPECT_EQ(*std::max_element(late.begin(), late.end()), 0.0);
}
