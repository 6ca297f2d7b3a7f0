// The commissioning tool: argument checks, and every command against the simulator over a pty.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <sstream>

#include "modbus_rtu_driver/sim/simulator.h"
#include "modbus_rtu_driver/tools/commission.h"

using namespace modbus_rtu_driver;

namespace {

std::string parseError(const std::vector<std::string>& args) {
  CommissionCommand c;
  std::string error;
  return parseCommission(args, &c, &error) ? std::string() : error;
}

class CommissionVsSimulator : public ::testing::Test {
 protected:
  void start(std::vector<SimulatorConfig::Entry> devices) {
    SimulatorConfig config;
    config.devices = std::move(devices);
    SimulatorOptions options;
    options.link = "/tmp/modbus_rtu_gtest_commission_" + std::to_string(getpid()) + "/tty";
    sim_ = std::make_unique<Simulator>(config, options);
    ASSERT_TRUE(sim_->start(nullptr));
  }
  // Runs the tool with `args` (after --port); `input` is what the user types.
  int run(std::vector<std::string> args, const std::string& input = "") {
    args.insert(args.begin(), {"--port", sim_->link(), "--timeout", "0.1"});
    CommissionCommand c;
    std::string error;
    out_.str("");
    err_.str("");
    if (!parseCommission(args, &c, &error)) {
      err_ << error;
      return kExitBadArguments;
    }
    std::istringstream in(input);
    return runCommission(c, in, out_, err_, stop_);
  }
  uint64_t framesSeen() {
    std::istringstream in(sim_->command("frames").substr(3));
    uint64_t frames = 0;
    in >> frames;
    return frames;
  }

  std::unique_ptr<Simulator> sim_;
  std::ostringstream out_, err_;
  std::atomic<bool> stop_{false};
};

}  // namespace

TEST(CommissionArgs, BadValuesNameTheOptionAndRange) {
  const std::vector<std::string> port = {"--port", "/dev/null"};
  auto with = [&](std::vector<std::string> rest) {
    rest.insert(rest.begin(), port.begin(), port.end());
    return parseError(rest);
  };
  EXPECT_NE(parseError({"scan"}).find("--port"), std::string::npos);
  EXPECT_NE(
      with({"set-address", "--type", "ld58a08", "0"}).find("new address: '0' is outside 1-247"),
      std::string::npos);
  EXPECT_NE(with({"set-address", "--type", "ld58a08", "248"}).find("1-247"), std::string::npos);
  EXPECT_NE(with({"set-address", "--type", "lc_relay8", "256"}).find("1-255"), std::string::npos);
  EXPECT_EQ(with({"set-address", "--type", "lc_relay8", "255"}), "");
  EXPECT_NE(with({"set-address", "--type", "relay", "3"}).find("--type"), std::string::npos);
  EXPECT_NE(with({"set-baud", "--type", "ld58a08", "--address", "1", "9"})
                .find("baud: '9' is outside 1200-115200"),
            std::string::npos);
  EXPECT_NE(with({"set-baud", "--type", "lc_relay8", "--address", "1", "115200"})
                .find("4800, 9600, 19200"),
            std::string::npos);
  EXPECT_NE(with({"set-parity", "--address", "1", "mark"}).find("parity: 'mark'"),
            std::string::npos);
  EXPECT_NE(with({"set-return-delay", "--address", "1", "1001"}).find("0-1000"), std::string::npos);
  EXPECT_NE(with({"set-return-delay", "--address", "1", "30"}).find("multiple of 40"),
            std::string::npos);
  EXPECT_NE(with({"read", "--address", "1", "bits", "0"}).find("table"), std::string::npos);
  EXPECT_NE(with({"read", "--address", "1", "holding", "0", "126"}).find("count"),
            std::string::npos);
  EXPECT_NE(with({"write", "--address", "1", "coils", "0", "2"}).find("value"), std::string::npos);
  EXPECT_NE(with({"scan", "--bauds", "9601"}).find("--bauds"), std::string::npos);
  EXPECT_NE(with({"scan", "--from", "9", "--to", "3"}).find("--to"), std::string::npos);
  EXPECT_NE(with({"frobnicate"}).find("command"), std::string::npos);
  EXPECT_NE(with({"scan", "--colour", "red"}).find("--colour: unknown option"), std::string::npos);
}

TEST_F(CommissionVsSimulator, ScanFindsTheConfiguredDevicesAndNoGhosts) {
  start({{"lc_relay8", 255}, {"ld58a08", 1}, {"yespeed_pdu", 2}});
  EXPECT_EQ(run({"--json", "scan", "--from", "1", "--to", "5"}), kExitOk) << err_.str();
  EXPECT_EQ(out_.str(),
            "{\"ok\":true,\"complete\":true,\"devices\":["
            "{\"address\":1,\"baud\":9600,\"parity\":\"none\",\"type\":\"ld58a08\"},"
            "{\"address\":2,\"baud\":9600,\"parity\":\"none\",\"type\":\"yespeed_pdu\"}]}\n");
  EXPECT_EQ(run({"scan", "--from", "250", "--to", "255"}), kExitOk) << err_.str();
  EXPECT_NE(out_.str().find("found lc_relay8 at address 255"), std::string::npos) << out_.str();
  EXPECT_EQ(out_.str().find("found ld58a08"), std::string::npos)
      << "no ghost at 0xFF: " << out_.str();
  EXPECT_NE(err_.str().find("1 device(s) found"), std::string::npos);
  EXPECT_EQ(run({"scan", "--from", "10", "--to", "12"}), kExitNotFound);
}

TEST_F(CommissionVsSimulator, Ld58a08AddressChangeAnswersAtTheNewAddressAtOnce) {
  start({{"ld58a08", 1}});
  EXPECT_EQ(run({"set-address", "--type", "ld58a08", "--address", "1", "9"}, "n\n"),
            kExitNotConfirmed);
  EXPECT_EQ(run({"read", "--address", "1", "holding", "253"}), kExitOk);
  EXPECT_EQ(run({"set-address", "--type", "ld58a08", "--address", "1", "9"}, "y\n"), kExitOk)
      << err_.str();
  EXPECT_EQ(run({"--json", "read", "--address", "9", "holding", "253"}), kExitOk);
  EXPECT_NE(out_.str().find("\"values\":[9]"), std::string::npos) << out_.str();
  EXPECT_EQ(run({"read", "--address", "1", "coils", "0"}), kExitNotFound);
  // Through 0xFF when the address is unknown.
  EXPECT_EQ(run({"get-address", "--type", "ld58a08"}), kExitOk);
  EXPECT_EQ(out_.str(), "address 9\n");
  EXPECT_EQ(run({"--yes", "set-address", "--type", "ld58a08", "4"}), kExitOk);
  EXPECT_EQ(run({"info", "--address", "4"}), kExitOk);
  EXPECT_NE(out_.str().find("address 4: ld58a08"), std::string::npos) << out_.str();
}

TEST_F(CommissionVsSimulator, LcBoardAddressChangeThroughAddressZero) {
  start({{"lc_relay8", 255}});
  EXPECT_EQ(run({"get-address", "--type", "lc_relay8"}), kExitOk);
  EXPECT_EQ(out_.str(), "address 255\n");
  EXPECT_EQ(run({"--yes", "set-address", "--type", "lc_relay8", "200"}), kExitOk) << err_.str();
  EXPECT_EQ(run({"read", "--address", "200", "coils", "0", "8"}), kExitOk);
  EXPECT_EQ(run({"read", "--address", "255", "coils", "0", "8"}), kExitNotFound);
  EXPECT_EQ(run({"--json", "scan", "--from", "199", "--to", "201"}), kExitOk);
  EXPECT_NE(
      out_.str().find("\"address\":200,\"baud\":9600,\"parity\":\"none\",\"type\":\"lc_relay8\""),
      std::string::npos)
      << out_.str();
}

TEST_F(CommissionVsSimulator, BaudChangeIsFoundAgainAfterAPowerCycle) {
  start({{"ld58a08", 1}});
  EXPECT_EQ(run({"--yes", "set-baud", "--type", "ld58a08", "--address", "1", "19200"}), kExitOk);
  EXPECT_NE(out_.str().find("after the device is powered off and on"), std::string::npos);
  EXPECT_EQ(run({"scan", "--from", "1", "--to", "2", "--bauds", "19200"}), kExitNotFound);
  EXPECT_EQ(sim_->command("power_cycle"), "ok");
  EXPECT_EQ(run({"--json", "scan", "--from", "1", "--to", "2", "--bauds", "9600,19200"}), kExitOk);
  EXPECT_NE(
      out_.str().find("{\"address\":1,\"baud\":19200,\"parity\":\"none\",\"type\":\"ld58a08\"}"),
      std::string::npos)
      << out_.str();
  EXPECT_EQ(out_.str().find("\"baud\":9600"), std::string::npos) << out_.str();
}

TEST_F(CommissionVsSimulator, RefusedAndUnconfirmedChangesSendNothing) {
  start({{"ld58a08", 1}});
  const uint64_t before = framesSeen();
  EXPECT_EQ(run({"set-parity", "--address", "1", "odd"}, ""), kExitNotConfirmed);  // EOF = no
  EXPECT_EQ(run({"set-return-delay", "--address", "1", "1001"}), kExitBadArguments);
  EXPECT_EQ(run({"set-address", "--type", "ld58a08", "--address", "1", "0"}), kExitBadArguments);
  EXPECT_EQ(framesSeen(), before);
  // A device that refuses gets its own exit code.
  EXPECT_EQ(run({"read", "--address", "1", "holding", "5"}), kExitRefused);
  EXPECT_NE(err_.str().find("illegal data address"), std::string::npos) << err_.str();
}

TEST_F(CommissionVsSimulator, WriteThenWatchPrintsChangesOnly) {
  start({{"lc_relay8", 255}});
  EXPECT_EQ(run({"write", "--address", "255", "coils", "0", "1", "0", "1"}), kExitOk) << err_.str();
  EXPECT_EQ(sim_->command("get 255 coil 0 3"), "ok 1 0 1");
  EXPECT_EQ(
      run({"watch", "--address", "255", "coils", "0", "3", "--interval", "0.02", "--count", "5"}),
      kExitOk);
  EXPECT_EQ(out_.str(), "coils 0: 1\ncoils 1: 0\ncoils 2: 1\n");  // one print: nothing changed
}

TEST(CommissionExecutable, BadArgumentsExitWith2AndHelpWith0) {
  const std::string exe = COMMISSION_EXE;
  EXPECT_EQ(WEXITSTATUS(std::system(
                (exe + " --port /dev/null set-parity --address 1 mark 2>/dev/null").c_str())),
            kExitBadArguments);
  EXPECT_EQ(WEXITSTATUS(std::system((exe + " --help >/dev/null").c_str())), 0);
  EXPECT_EQ(WEXITSTATUS(std::system(
                (exe + " --port /nonexistent/tty read --address 1 coils 0 2>/dev/null").c_str())),
            kExitBusError);
}
