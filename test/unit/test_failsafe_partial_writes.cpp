// docs/failsafe.md, "A command whose answer was lost" (the port failed while it went out) and
// "A write that failed after part of it was done": the node's own classes (BusRuntime: the bus
// node's DeviceCommands, DeviceFailsafe and scheduler) against the simulated boards in memory,
// under a manual clock. The state asserted is the simulated board's, not the node's.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "modbus_rtu_driver/devices/ld58a08.h"
#include "modbus_rtu_driver/runtime/bus_runtime.h"
#include "modbus_rtu_driver/sim/sim_lc_relay8.h"
#include "modbus_rtu_driver/sim/sim_ld58a08.h"
#include "modbus_rtu_driver/simulation/memory_link.h"

using namespace modbus_rtu_driver;

namespace {

// The memory link, and one armed failure: the next request of `function` either reaches the
// board and then the port fails (kIo, the port lost), or does not reach it and is answered
// with `error`.
class FailingLink : public Transport {
 public:
  explicit FailingLink(MemoryLink& link) : link_(link) {}
  void failNext(FunctionCode function, bool delivered, ErrorKind error) {
    function_ = function;
    delivered_ = delivered;
    error_ = error;
    armed_ = true;
  }
  Result execute(const Request& request) override {
    link_.beginTransaction();
    if (!armed_ || request.function != function_) return link_.execute(request);
    armed_ = false;
    if (delivered_) link_.execute(request);
    if (error_ == ErrorKind::kIo) link_.setPortLost(true);
    return Result::failure(error_, request.describe() + ": failed (test)");
  }
  bool connect(std::string* error) override { return link_.connect(error); }
  bool connected() const override { return link_.connected(); }
  void disconnect() override { link_.disconnect(); }

 private:
  MemoryLink& link_;
  bool armed_ = false;
  FunctionCode function_ = FunctionCode::kWriteSingleCoil;
  bool delivered_ = true;
  ErrorKind error_ = ErrorKind::kIo;
};

// An LC board at 1 and an LD58A08 at 2, every safe state off, restored on a restart.
struct PartialWrites : ::testing::Test {
  ManualClock clock;
  std::unique_ptr<MemoryLink> memory;
  std::unique_ptr<FailingLink> link;
  std::unique_ptr<BusRuntime> node;
  std::vector<std::string> reports;

  void SetUp() override {
    LinkConfig config;
    config.port = "memory";
    config.baud = 19200;
    config.response_timeout = 0.1;
    config.retries = 1;
    config.late_reply_guard = 0;
    memory = std::make_unique<MemoryLink>(config, clock);
    SimLineSettings line;
    line.baud = 19200;
    memory->addDevice(std::make_unique<SimLcRelay8>(1, line));
    memory->addDevice(std::make_unique<SimLd58a08>(2, line));
    link = std::make_unique<FailingLink>(*memory);
    BusConfig bus;  // no heartbeat here: the writes are the subject
    const char* names[] = {"relays", "pwm"};
    const char* types[] = {"lc_relay8", "ld58a08"};
    for (int d = 0; d < 2; ++d) {
      DeviceConfig device;
      device.name = names[d];
      device.type = types[d];
      device.address = d + 1;
      device.poll_rate = 5.0;
      device.failsafe.on_restart = OnRestart::kRestore;
      device.failsafe.safe_state.assign(8, SafeState::kOff);
      device.failsafe.command_timeout.assign(8, 0.0);
      bus.devices.push_back(device);
    }
    BusRuntime::Options options;
    options.clock = &clock;
    options.stepped = true;
    node = std::make_unique<BusRuntime>(bus, *link, std::move(options));
    for (const auto& unit : node->units()) {
      DeviceUnit::Observers seen;
      seen.report = [this](const FailsafeReport& r, const std::string& text) {
        reports.push_back(r.device + ": " + text);
      };
      unit->observe(std::move(seen));
    }
    // The start's wait: half a second of the bus, whether or not its writes are done.
    node->start([this](const BusRuntime::Pending&, Clock::time_point) { run(0.5); });
    run(1.0);
  }
  // The bus thread's jobs and polls, in simulated time.
  void run(double seconds) {
    const auto end = clock.now() + std::chrono::duration_cast<Clock::duration>(
                                       std::chrono::duration<double>(seconds));
    while (clock.now() < end) {
      Clock::time_point next = Clock::time_point::max();
      if (node->scheduler().step(&next)) continue;
      clock.advanceTo(std::min(next, end));
    }
  }
  uint16_t board(uint8_t address, Table table, uint16_t at) const {
    uint16_t value = 0;
    memory->device(address)->read(table, at, clock.now(), &value);
    return value;
  }
  std::string restarts() const {
    std::string found;
    for (const std::string& r : reports)
      if (r.find("restart") != std::string::npos) found += r + "\n";
    return found;
  }
};

}  // namespace

TEST_F(PartialWrites, AUsersWriteThatWentOutBeforeThePortFailedIsTakenAsFound) {
  link->failNext(FunctionCode::kWriteSingleCoil, /*delivered=*/true, ErrorKind::kIo);
  auto set = node->unit("relays")->set({3}, {true});
  run(0.3);
  EXPECT_FALSE(set.get().ok()) << "the caller is told it failed";
  ASSERT_EQ(board(1, Table::kCoil, 3), 1) << "the board heard it";
  memory->setPortLost(false);
  run(8.0);
  EXPECT_EQ(board(1, Table::kCoil, 3), 1) << "no restore wrote it back: nobody asked";
  EXPECT_EQ(restarts(), "");
}

TEST_F(PartialWrites, AMergedWriteWhoseLaterFrameFailedLeavesTheEarlierOneAsFound) {
  // Channels 0-1 go in one FC15, channel 5 in an FC05 the board refuses.
  link->failNext(FunctionCode::kWriteSingleCoil, /*delivered=*/false, ErrorKind::kException);
  auto set = node->unit("relays")->set({0, 1, 5}, {true, true, true});
  run(0.3);
  const Result written = set.get();
  EXPECT_FALSE(written.ok());
  EXPECT_NE(written.message.find("outputs 0, 1 were written before"), std::string::npos)
      << written.message;
  ASSERT_EQ(board(1, Table::kCoil, 5), 0);
  run(8.0);
  EXPECT_EQ(board(1, Table::kCoil, 0), 1) << "not written back";
  EXPECT_EQ(board(1, Table::kCoil, 1), 1) << "not written back";
  EXPECT_EQ(board(1, Table::kCoil, 5), 0) << "never written";
  EXPECT_EQ(restarts(), "");
}

TEST_F(PartialWrites, AContinuousRunStoppedBeforeAFailedPlainWriteIsNotStartedAgain) {
  PwmSettings pwm;
  pwm.channel = 0;
  pwm.period = 1.0;
  pwm.on_time = 0.5;
  pwm.pulses = 0;  // continuous: a restore would start it again
  auto started = node->unit("pwm")->setPwm(pwm);
  run(0.5);
  ASSERT_TRUE(started.get().ok());
  const uint16_t enable = Ld58a08::pwmRegister(0) + 2;
  ASSERT_EQ(board(2, Table::kHoldingRegister, enable), 0xFFFF);
  // out0 off: the run is stopped (confirmed), then the coil write never reaches the board.
  link->failNext(FunctionCode::kWriteSingleCoil, /*delivered=*/false, ErrorKind::kIo);
  auto set = node->unit("pwm")->set({0}, {false});
  run(0.3);
  EXPECT_FALSE(set.get().ok());
  ASSERT_EQ(board(2, Table::kHoldingRegister, enable), 0) << "stopped";
  memory->setPortLost(false);
  run(10.0);
  EXPECT_EQ(board(2, Table::kHoldingRegister, enable), 0) << "not started again: nobody asked";
  EXPECT_EQ(restarts(), "");
}
