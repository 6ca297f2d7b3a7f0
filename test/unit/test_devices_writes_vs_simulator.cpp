// Writes of non-adjacent channels against the simulator over a real pty (issue 24, item 4): a
// flash running on a relay between two written ones keeps running and reverts by itself. The
// simulator models the LC board's "a relay write cancels its flash" (docs/devices/lc_relay8.md),
// so a frame over the relay in between would leave it on for good.
#include <gtest/gtest.h>
#include <unistd.h>

#include "modbus_rtu_driver/core/link/rtu_link.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/devices/output_batch.h"
#include "modbus_rtu_driver/sim/simulator.h"
#include "wait_for.h"

using namespace modbus_rtu_driver;

namespace {

class WritesVsSimulator : public ::testing::Test {
 protected:
  void SetUp() override {
    SimulatorConfig config;
    config.devices = {{"lc_relay8", 255}};
    SimulatorOptions options;
    options.link = "/tmp/modbus_rtu_gtest_writes_" + std::to_string(getpid()) + "/tty";
    sim_ = std::make_unique<Simulator>(config, options);
    std::string error;
    ASSERT_TRUE(sim_->start(&error)) << error;
    LinkConfig c;
    c.port = sim_->link();
    c.baud = 9600;
    c.response_timeout = 0.5;
    c.retries = 0;
    link_ = std::make_unique<RtuLink>(c);
    ASSERT_TRUE(link_->connect(&error)) << error;
  }
  std::string sim(const std::string& command) { return sim_->command(command); }

  std::unique_ptr<Simulator> sim_;
  std::unique_ptr<RtuLink> link_;
};

}  // namespace

TEST_F(WritesVsSimulator, AFlashBetweenTwoWrittenRelaysKeepsRunning) {
  DeviceConfig dc;
  dc.name = "relays";
  dc.type = "lc_relay8";
  dc.address = 255;
  LcRelay8 board(dc);
  // Relay 1 closes for 3 s, then opens by itself.
  Result r = board.pulse(*link_, 1, true, 3.0);
  ASSERT_TRUE(r.ok()) << r.message;
  ASSERT_EQ(sim("get 255 coil 1"), "ok 1");
  r = OutputBatch::write(board, *link_, {0, 2}, {true, true});
  ASSERT_TRUE(r.ok()) << r.message;
  // The write came while the flash ran (3 s is far longer than two frames at 9600 baud); if it
  // already ended, this run proves nothing.
  ASSERT_EQ(sim("get 255 coil 0 3"), "ok 1 1 1") << "the flash ended before the write";
  // The flash still runs: relay 1 opens by itself; relays 0 and 2 stay as written.
  EXPECT_TRUE(waitFor([&] { return sim("get 255 coil 1") == "ok 0"; }, 15.0))
      << "relay 1 never opened: the write cancelled its flash";
  EXPECT_EQ(sim("get 255 coil 0 3"), "ok 1 0 1");
}
