// The simulator's RTU-over-TCP gateway with the real RtuOverTcpLink: the same line and devices
// as the pty (reads, a write checked in the simulator, the LC board at 255 and its command at
// address 0), dropped connections (a gateway reboot) and the reconnect.
#include <gtest/gtest.h>
#include <unistd.h>

#include "modbus_rtu_driver/core/link/rtu_over_tcp_link.h"
#include "modbus_rtu_driver/sim/simulator.h"
#include "wait_for.h"

using namespace modbus_rtu_driver;

namespace {

class SimGatewayTest : public ::testing::Test {
 protected:
  void SetUp() override {
    SimulatorConfig config;
    config.devices = {{"lc_relay8", 255}, {"yespeed_pdu", 2}};
    SimulatorOptions options;
    options.link = "/tmp/modbus_rtu_gtest_gw_" + std::to_string(getpid()) + "/tty";
    options.rtu_tcp_port = 0;
    sim_ = std::make_unique<Simulator>(config, options);
    std::string error;
    ASSERT_TRUE(sim_->start(&error)) << error;
    ASSERT_GT(sim_->rtuTcpPort(), 0);
    LinkConfig c;
    c.port = "rtu+tcp://127.0.0.1:" + std::to_string(sim_->rtuTcpPort());
    c.network_allowance = 0.2;
    c.retries = 0;
    link_ = std::make_unique<RtuOverTcpLink>(c);
    ASSERT_TRUE(link_->connect(&error)) << error;
  }
  std::string sim(const std::string& command) { return sim_->command(command); }

  std::unique_ptr<Simulator> sim_;
  std::unique_ptr<RtuOverTcpLink> link_;
};

}  // namespace

TEST_F(SimGatewayTest, ServesTheSameLineAsThePty) {
  Result r = link_->execute(Request::writeSingleCoil(255, 2, true));
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(sim("get 255 coil 0 8"), "ok 0 0 1 0 0 0 0 0");
  r = link_->execute(Request::readCoils(255, 0, 8));
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, (std::vector<uint16_t>{0, 0, 1, 0, 0, 0, 0, 0}));
  // The LC board's "read address" at 0, answered when it is alone... here the PDU hears it too
  // as a broadcast read, which it does not answer.
  Request at_zero = Request::readHoldingRegisters(kBroadcastAddress, 0, 1);
  at_zero.single_device_at_zero = true;
  r = link_->execute(at_zero);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(r.values, std::vector<uint16_t>{255});
  EXPECT_EQ(sim("frames").substr(0, 5), "ok 3 ");
}

TEST_F(SimGatewayTest, ADroppedConnectionIsAnIoErrorAndTheLinkReconnects) {
  ASSERT_TRUE(link_->execute(Request::readHoldingRegisters(2, 0, 1)).ok());
  EXPECT_EQ(sim("gateway"), "ok port " + std::to_string(sim_->rtuTcpPort()) +
                                " connections 1 accepted 1 dropped 0");
  // A reboot: the connection goes, and for a while nobody listens.
  EXPECT_EQ(sim("gateway_drop 300"), "ok");
  Result r = link_->execute(Request::writeSingleCoil(255, 1, true));
  EXPECT_EQ(r.error, ErrorKind::kIo) << r.message;
  EXPECT_FALSE(link_->connected());
  std::string error;
  EXPECT_FALSE(link_->connect(&error));  // nobody listens while it reboots
  EXPECT_NE(error.find("cannot connect"), std::string::npos) << error;
  ASSERT_TRUE(waitFor([&] { return link_->connect(&error); }, 10)) << error;
  EXPECT_EQ(link_->stats().reconnects, 1u);
  r = link_->execute(Request::writeSingleCoil(255, 1, true));
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(sim("get 255 coil 1"), "ok 1");
  EXPECT_EQ(sim("gateway_drop x"), "error gateway_drop: MS 'x' is not 0-600000");
}

TEST(SimGateway, CommandsSayWhenThereIsNoGateway) {
  SimulatorConfig config;
  config.devices = {{"yespeed_pdu", 2}};
  SimulatorOptions options;
  options.link = "/tmp/modbus_rtu_gtest_nogw_" + std::to_string(getpid()) + "/tty";
  Simulator sim(config, options);
  ASSERT_TRUE(sim.start(nullptr));
  EXPECT_EQ(sim.rtuTcpPort(), 0);
  EXPECT_NE(sim.command("gateway_drop").find("--rtu-tcp"), std::string::npos);
}
