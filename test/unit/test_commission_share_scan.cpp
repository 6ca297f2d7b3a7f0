// modbus_rtu_commission's scan through a Modbus TCP gateway (issue 32 item 16): the real tool
// (parseCommission + runCommission, a tcp:// port) against the real share (ShareGateway on
// 127.0.0.1, an ephemeral port) over a bus where one address answers and the others stay silent
// until the gateway gives up on them, as the node's share does: exception 0B, late. The gateway's
// 0B is nobody's answer, and a scan must wait for it rather than leave requests queued behind.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "modbus_rtu_driver/core/server/share_gateway.h"
#include "modbus_rtu_driver/tools/commission.h"

using namespace modbus_rtu_driver;

namespace {

constexpr uint8_t kDevice = 8;
// How long the far line stays silent before the gateway answers 0B: longer than the tool's
// serial scan timeout (0.081 s + the network allowance), as the node's response timeout is.
constexpr auto kSilence = std::chrono::milliseconds(300);

// The line behind the gateway: a device at kDevice answers reads with zeros and refuses
// writes; every other address is silent (the link's timeout, after kSilence).
class OneDeviceLine : public Transport {
 public:
  Result execute(const Request& r) override {
    if (r.slave != kDevice) {
      std::this_thread::sleep_for(kSilence);
      return Result::failure(ErrorKind::kTimeout, "no reply");
    }
    if (!isReadFunction(r.function))
      return Result::failure(ErrorKind::kException, "refused", kIllegalFunction);
    return Result::success(std::vector<uint16_t>(r.count, 0));
  }
};

struct Share {
  Share() : scheduler(line) {
    ShareConfig config;
    config.enabled = true;
    config.server.port = 0;
    gateway = std::make_unique<ShareGateway>(scheduler, config);
  }
  ~Share() {
    scheduler.stop();  // pending answers call into the gateway: stop the bus first
    gateway.reset();
  }
  bool start() {
    scheduler.start();
    std::string error;
    return gateway->start(&error);
  }
  std::string port() const { return "tcp://127.0.0.1:" + std::to_string(gateway->server().port()); }

  OneDeviceLine line;
  BusScheduler scheduler;
  std::unique_ptr<ShareGateway> gateway;
};

struct ToolRun {
  int exit = -1;
  std::string out, err;
};

ToolRun commission(const std::vector<std::string>& args) {
  CommissionCommand cmd;
  std::string error;
  ToolRun run;
  if (!parseCommission(args, &cmd, &error)) {
    ADD_FAILURE() << error;
    return run;
  }
  std::istringstream in;
  std::ostringstream out, err;
  std::atomic<bool> stop{false};
  run.exit = runCommission(cmd, CommissionIo{in, out, err, stop, false});
  run.out = out.str();
  run.err = err.str();
  return run;
}

// The addresses a JSON scan lists.
std::vector<int> scanned(const ToolRun& run) {
  std::vector<int> addresses;
  const auto result = nlohmann::json::parse(run.out, nullptr, false);
  if (result.is_discarded() || !result.contains("devices")) {
    ADD_FAILURE() << "not a scan's JSON: " << run.out << run.err;
    return addresses;
  }
  EXPECT_TRUE(result.value("complete", false)) << run.out;
  for (const auto& device : result["devices"]) addresses.push_back(device["address"].get<int>());
  return addresses;
}

}  // namespace

// The tool's own timeout for a scan: the gateway's 0B comes after it, and each address must
// still get its own answer, not wait behind the requests given up before (a device missed).
TEST(CommissionScanThroughShare, WithTheDefaultTimeoutListsExactlyTheDeviceThatAnswers) {
  Share share;
  ASSERT_TRUE(share.start());
  const ToolRun run = commission({"--port", share.port(), "--json", "scan", "--addresses", "5-9"});
  EXPECT_EQ(scanned(run), std::vector<int>{kDevice}) << run.out << run.err;
  EXPECT_EQ(run.exit, kExitOk);
}

// A timeout above the gateway's: its 0B arrives in time and is no device.
TEST(CommissionScanThroughShare, TheGatewaysNoAnswerIsNoDevice) {
  Share share;
  ASSERT_TRUE(share.start());
  const ToolRun run = commission(
      {"--port", share.port(), "--timeout", "1", "--json", "scan", "--addresses", "5-9"});
  EXPECT_EQ(scanned(run), std::vector<int>{kDevice}) << run.out << run.err;
  EXPECT_EQ(run.exit, kExitOk);
  // The empty range: nothing found, exit "not found".
  const ToolRun empty = commission(
      {"--port", share.port(), "--timeout", "1", "--json", "scan", "--addresses", "5-6"});
  EXPECT_EQ(scanned(empty), std::vector<int>{});
  EXPECT_EQ(empty.exit, kExitNotFound);
}

// Outside a scan too: 0B through a gateway is "no answer" (exit 3), not a device's refusal (4).
TEST(CommissionScanThroughShare, AReadAtASilentAddressExitsNotFound) {
  Share share;
  ASSERT_TRUE(share.start());
  const ToolRun run =
      commission({"--port", share.port(), "read", "--address", "6", "holding_register", "0"});
  EXPECT_EQ(run.exit, kExitNotFound) << run.out << run.err;
  const ToolRun found =
      commission({"--port", share.port(), "read", "--address", "8", "holding_register", "0"});
  EXPECT_EQ(found.exit, kExitOk) << found.out << found.err;
}
