// Combinations an independent review found with outputs wrong (issue 48 items 1 and 2), on the
// node's own bus runtime (runtime/bus_runtime.h: the scheduler, fail-safes, commands and share)
// against the
// simulated devices in memory, under a manual clock. What is asserted is the simulated device's
// state, not the node's.
//   docs/failsafe.md, "What happens when": a broadcast (unit 0) confirms nothing;
//   docs/failsafe.md, "Generic devices": a signal set since the trigger is not written.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <future>
#include <memory>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/config/signal.h"
#include "modbus_rtu_driver/runtime/bus_runtime.h"
#include "modbus_rtu_driver/sim/sim_generic.h"
#include "modbus_rtu_driver/sim/sim_lc_relay8.h"
#include "modbus_rtu_driver/simulation/memory_link.h"

using namespace modbus_rtu_driver;

namespace {

constexpr uint8_t kPump = 0, kValve = 1, kLamp = 2, kFan = 3;

// The bus: the node's parts on a memory line, its deadlines checked at their period and the bus
// heartbeat fed while `alive`.
struct NodeOnMemoryLine : ::testing::Test {
  ManualClock clock;
  std::unique_ptr<MemoryLink> memory;
  std::unique_ptr<BusRuntime> node;
  std::vector<std::string> reports;
  bool alive = true;

  // The node's bus, `devices` on it, a bus heartbeat of 0.5 s, the share open (no sockets).
  void start(std::vector<DeviceConfig> devices) {
    BusConfig config;
    config.devices = std::move(devices);
    config.heartbeat_topic = "/alive";
    config.heartbeat_timeout = 0.5;
    config.share.enabled = true;
    config.share.broadcast_turnaround = 0;  // a real sleep on the bus thread otherwise
    BusRuntime::Options options;
    options.clock = &clock;
    options.stepped = true;
    node = std::make_unique<BusRuntime>(std::move(config), *memory, std::move(options));
    for (const auto& unit : node->units()) {
      DeviceUnit::Observers seen;
      seen.report = [this](const FailsafeReport& r, const std::string& text) {
        reports.push_back(r.device + " " + text);
      };
      unit->observe(std::move(seen));
    }
    std::string error;
    ASSERT_TRUE(node->share()->open(&error)) << error;
    // The start's wait: half a second of the bus, whether or not its writes are done.
    node->start([this](const BusRuntime::Pending&, Clock::time_point) { run(0.5); });
    run(1.0);
  }
  void makeLine() {
    LinkConfig config;
    config.port = "memory";
    config.baud = 19200;
    config.response_timeout = 0.1;
    config.retries = 1;
    config.late_reply_guard = 0;
    memory = std::make_unique<MemoryLink>(config, clock);
  }
  // The bus thread's jobs and polls, and the node's deadline timer, in simulated time.
  void run(double seconds) {
    const auto end = clock.now() + std::chrono::duration_cast<Clock::duration>(
                                       std::chrono::duration<double>(seconds));
    const auto period = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(node->checkPeriod() > 0 ? node->checkPeriod() : 0.05));
    auto check = clock.now() + period;
    while (clock.now() < end) {
      if (alive) node->feedHeartbeat();
      if (clock.now() >= check) {
        node->checkDeadlines();
        check += period;
      }
      Clock::time_point next = Clock::time_point::max();
      if (node->scheduler().step(&next)) continue;
      clock.advanceTo(std::min({next, end, check}));
    }
  }
  // A share client's request; the future holds the transaction's outcome.
  std::future<Result> share(const Request& request) const {
    auto outcome = std::make_shared<std::promise<Result>>();
    std::future<Result> f = outcome->get_future();
    node->share()->forward(
        request, [](const Bytes&) {}, [outcome](const Result& r) { outcome->set_value(r); });
    return f;
  }
  uint16_t board(uint8_t address, Table table, uint16_t at) const {
    uint16_t value = 0;
    memory->device(address)->read(table, at, clock.now(), &value);
    return value;
  }
};

DeviceConfig relayBoard(const std::string& name, int address) {
  DeviceConfig d;
  d.name = name;
  d.type = "lc_relay8";
  d.address = address;
  d.poll_rate = 5.0;
  d.failsafe.on_restart = OnRestart::kRestore;
  d.failsafe.safe_state.assign(8, SafeState::kLeave);
  d.failsafe.safe_state[kPump] = d.failsafe.safe_state[kValve] = SafeState::kOff;
  d.failsafe.safe_state[kFan] = SafeState::kOff;
  d.failsafe.command_timeout.assign(8, 0.0);
  return d;
}

}  // namespace

// Item 1: a heartbeat is lost while board b is silent (its safe write owed); a share client
// broadcasts FC15 pump, valve, lamp, fan on. Board a heard it, b did not: nothing confirms it.
// The lamp's safe state is "leave it": on a it stays as found; pump, valve and fan are held safe.
TEST_F(NodeOnMemoryLine, AShareBroadcastConfirmsNothingOnABoardThatNeverHeardIt) {
  makeLine();
  SimLineSettings line;
  line.baud = 19200;
  memory->addDevice(std::make_unique<SimLcRelay8>(1, line));
  memory->addDevice(std::make_unique<SimLcRelay8>(2, line));
  start({relayBoard("a", 1), relayBoard("b", 2)});
  for (const char* name : {"a", "b"}) {
    auto set = node->unit(name)->set({kPump, kValve}, {true, true});
    run(0.3);
    ASSERT_TRUE(set.get().ok()) << name;
  }
  memory->faults(2).silent = true;
  run(1.0);  // b fails its polls
  alive = false;
  run(2.0);  // the heartbeat is lost: a safe, b's safe write owed
  ASSERT_EQ(board(1, Table::kCoil, kPump), 0);
  ASSERT_EQ(board(2, Table::kCoil, kPump), 1) << "b never heard the safe write";
  auto broadcast =
      share(Request::writeMultipleCoils(kBroadcastAddress, 0, {true, true, true, true}));
  run(0.5);
  ASSERT_TRUE(broadcast.get().ok()) << "sent";
  ASSERT_EQ(board(1, Table::kCoil, kLamp), 1) << "a heard it";
  ASSERT_EQ(board(2, Table::kCoil, kLamp), 0) << "b did not";
  memory->faults(2).silent = false;
  run(8.0);  // b answers again; the heartbeat stays lost
  std::string log;
  for (const std::string& r : reports) log += r + "\n";
  EXPECT_EQ(board(2, Table::kCoil, kPump), 0) << "held safe: the owed safe write\n" << log;
  EXPECT_EQ(board(2, Table::kCoil, kValve), 0) << "held safe: the owed safe write\n" << log;
  EXPECT_EQ(board(2, Table::kCoil, kFan), 0) << "nobody switched b's fan on\n" << log;
  EXPECT_EQ(board(2, Table::kCoil, kLamp), 0) << "nobody switched b's lamp on\n" << log;
  // a: the held channels a poll found on are written safe again; the lamp is as found.
  EXPECT_EQ(board(1, Table::kCoil, kPump), 0) << log;
  EXPECT_EQ(board(1, Table::kCoil, kValve), 0) << log;
  EXPECT_EQ(board(1, Table::kCoil, kFan), 0) << log;
  EXPECT_EQ(board(1, Table::kCoil, kLamp), 1) << log;
}

// Item 2: the heartbeat is lost while a generic drive is silent (its safe values owed); it
// answers again, and the user sets run on and speed 30 Hz, confirmed, before its next poll.
TEST_F(NodeOnMemoryLine, AGenericDevicesOwedSafeValuesDoNotOverwriteANewerSet) {
  makeLine();
  DeviceConfig drive;
  drive.name = "drive";
  drive.type = "generic";
  drive.address = 4;
  drive.poll_rate = 0.2;  // a poll every 5 s: the user's set comes before it
  drive.generic = parseSignalMap(
      YAML::Load("signals:\n"
                 "  - {name: run, table: coil, address: 0, type: bool, writable: true,\n"
                 "     safe_value: 0}\n"
                 "  - {name: speed, table: holding_register, address: 0x10, type: int16,\n"
                 "     scale: 0.1, unit: Hz, writable: true, min: 0, max: 50, safe_value: 0}\n"),
      "devices/drive/", "");
  SimLineSettings line;
  line.baud = 19200;
  SimGenericConfig gc;
  gc.map = drive.generic;
  memory->addDevice(std::make_unique<SimGeneric>(4, line, gc));
  start({drive});
  memory->faults(4).silent = true;
  alive = false;
  run(1.0);  // lost: the safe write finds the drive silent, its safe values owed
  memory->faults(4).silent = false;
  auto set_run = node->unit("drive")->writeSignal(0, 1.0);
  auto set_speed = node->unit("drive")->writeSignal(1, 30.0);
  run(0.5);
  ASSERT_TRUE(set_run.get().ok());
  ASSERT_TRUE(set_speed.get().ok());
  run(10.0);  // polls answer again
  std::string log;
  for (const std::string& r : reports) log += r + "\n";
  EXPECT_EQ(board(4, Table::kCoil, 0), 1) << "run, set after the trigger\n" << log;
  EXPECT_EQ(board(4, Table::kHoldingRegister, 0x10), 300) << "30 Hz, set after the trigger\n"
                                                          << log;
}
