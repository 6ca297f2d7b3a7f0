// The simulator's configuration, control commands (in-process and over the Unix socket), power
// cycle and state file.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <thread>

#include "modbus_rtu_driver/sim/simulator.h"
#include "test_sim_helpers.h"

using namespace modbus_rtu_driver;
using namespace modbus_rtu_driver::simtest;

namespace {

std::string configError(const std::string& yaml) {
  SimulatorConfig c;
  std::string error;
  return parseSimulatorConfig(yaml, &c, &error) ? "accepted" : error;
}

std::string fileText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TEST(SimConfig, TheShippedConfigLoads) {
  SimulatorConfig c;
  std::string error;
  ASSERT_TRUE(loadSimulatorConfig(REPO_DIR "/config/simulator.yaml", &c, &error)) << error;
  ASSERT_EQ(c.devices.size(), 3u);
  EXPECT_EQ(c.devices[0].type, "lc_relay8");
  EXPECT_EQ(c.devices[0].address, 8);  // not 255: the LD58A08 beside it answers 0xFF too
  EXPECT_EQ(c.factory.baud, 9600);
  EXPECT_EQ(c.factory.parity, Parity::kNone);
  EXPECT_FALSE(c.pace);
}

TEST(SimConfig, BadConfigsAreRefusedNamingTheKey) {
  const std::string devices = "devices: [{type: ld58a08, address: 1}]\n";
  EXPECT_EQ(configError("baud: 19200\nparity: even\npace: true\n" + devices), "accepted");
  EXPECT_EQ(configError("bauds: 9600\n" + devices),
            "bauds: unknown key (known keys: baud, devices, pace, parity)");
  EXPECT_EQ(configError("baud: 9601\n" + devices),
            "baud: 9601 is not a standard rate (1200-115200)");
  EXPECT_EQ(configError("baud: fast\n" + devices), "baud: 'fast' is not a number");
  // The node's helpers (core/config/config_yaml.h): a fraction is named as such, a list as a list.
  EXPECT_EQ(configError("baud: 9600.5\n" + devices), "baud: '9600.5' is not a whole number");
  EXPECT_EQ(configError("devices: [{type: lc_relay8, address: [1]}]"),
            "devices[0]/address: a list is not a number");
  EXPECT_EQ(configError("parity: mark\n" + devices),
            "parity: 'mark' is not one of none, even, odd");
  EXPECT_EQ(configError("parity: E\n" + devices),
            "parity: 'E' is not one of none, even, odd (write 'even')");
  EXPECT_EQ(configError("pace: maybe\n" + devices),
            "pace: 'maybe' is not one of on/off, true/false, yes/no, 1/0");
  EXPECT_EQ(configError("baud: 9600\n"), "devices: missing or not a list of {type, address}");
  EXPECT_EQ(
      configError("devices: [{type: plc, address: 1}]"),
      "devices[0]/type: 'plc' is not a simulated type (generic, lc_relay8, ld58a08, yespeed_pdu)");
  EXPECT_EQ(
      configError("devices: [{type: lc_relay8, address: 255}, {type: ld58a08, address: 249}]"),
      "devices[1]/address: 249 is outside 1-248 for ld58a08");
  EXPECT_EQ(configError("devices: [{type: ld58a08, address: 248}]"), "accepted");
  EXPECT_EQ(configError("devices: [{type: yespeed_pdu, address: 248}]"),
            "devices[0]/address: 248 is outside 1-247 for yespeed_pdu");
  EXPECT_EQ(configError("devices: [{type: lc_relay8, address: 0}]"),
            "devices[0]/address: 0 is outside 1-255 for lc_relay8");
  EXPECT_EQ(configError("devices: [{type: lc_relay8, address: x}]"),
            "devices[0]/address: 'x' is not a number");
  EXPECT_EQ(configError("devices: [{type: lc_relay8}]"), "devices[0]/address: missing");
  EXPECT_EQ(configError("devices: [{type: lc_relay8, address: 1, baud: 4800}]"),
            "devices[0]/baud: unknown key (known keys: address, type)");
  EXPECT_EQ(configError("devices: [lc_relay8]"), "devices[0]: not a map {type: ..., address: ...}");
  EXPECT_EQ(configError("- 1\n- 2\n"), "the file is not a map of baud, parity, pace and devices");
  EXPECT_EQ(configError("devices: [").rfind("not valid YAML: ", 0), 0u);
  SimulatorConfig c;
  std::string error;
  EXPECT_FALSE(loadSimulatorConfig("/nonexistent.yaml", &c, &error));
  EXPECT_EQ(error, "cannot read the file");
}

TEST(SimControl, CommandsAndTheirErrors) {
  ScratchDir dir;
  auto sim = started(dir, {{"lc_relay8", 255}, {"ld58a08", 1}, {"yespeed_pdu", 2}});
  EXPECT_EQ(sim->command("info"),
            "ok #0:lc_relay8:255:9600:N #1:ld58a08:1:9600:N #2:yespeed_pdu:2:9600:N");
  EXPECT_EQ(sim->command("set 0xFF coil 0 1 0 1"), "ok");
  EXPECT_EQ(sim->command("get #0 coil 0 4"), "ok 1 0 1 0");
  EXPECT_EQ(sim->command("set #0 discrete_input 7 1"), "ok");
  EXPECT_EQ(sim->command("get 255 discrete_input 6 2"), "ok 0 1");
  EXPECT_EQ(sim->command("set 2 input_register 0 -55"), "ok");
  EXPECT_EQ(sim->command("get 2 input_register 0"), "ok 65481");
  EXPECT_EQ(sim->command("set 2 holding_register 0 1900 1850"), "ok")
      << "one write, checked as a whole";
  EXPECT_EQ(sim->command("set 2 holding_register 0 1700"), "error illegal data value (03) at 0");
  EXPECT_EQ(sim->command("get 1 holding_register 0x80"), "ok 0");
  EXPECT_EQ(sim->command("get 1 holding_register 5"), "error illegal data address (02) at 5");
  EXPECT_EQ(sim->command("get 1 coil 6 4"), "error illegal data address (02) at 8");
  EXPECT_EQ(sim->command("get 1 discrete_input 0"), "error illegal function (01) at 0");
  EXPECT_EQ(sim->command("set 1 discrete_input 0 1"), "error illegal data address (02) at 0");
  EXPECT_EQ(sim->command("frames"), "ok 0 0 0");
  EXPECT_EQ(sim->command("bogus"), "error unknown command 'bogus' (try help)");
  EXPECT_EQ(sim->command("get 9 coil 0"), "error no device '9' (#index or address; see info)");
  EXPECT_EQ(sim->command("get #3 coil 0"), "error no device '#3' (#index or address; see info)");
  EXPECT_EQ(sim->command("get 1 relay 0").rfind("error table 'relay'", 0), 0u);
  EXPECT_EQ(sim->command("get 1 coil 70000").rfind("error address '70000'", 0), 0u);
  EXPECT_EQ(sim->command("get 1 coil 0 0"), "error count '0' is not 1-2000");
  EXPECT_EQ(sim->command("set 1 coil 0").rfind("error set needs at least one value", 0), 0u);
  EXPECT_EQ(sim->command("set 1 coil 0 2"), "error coil values are 0 or 1");
  EXPECT_EQ(sim->command("set 2 input_register 0 70000"), "error value '70000' is not 16 bits");
  EXPECT_EQ(sim->command("silence 1 2"),
            "error silence: '2' is not one of on/off, true/false, yes/no, 1/0");
  EXPECT_EQ(sim->command("silence 1 on"), "ok");  // the one set of on/off words (issue #33)
  EXPECT_EQ(sim->command("silence 1 no"), "ok");
  EXPECT_EQ(sim->command("silence 1"), "ok");
  EXPECT_EQ(sim->command("help").rfind("ok get set", 0), 0u);
}

TEST(SimControl, OverTheUnixSocketOneReplyLinePerCommand) {
  ScratchDir dir;
  auto sim = started(dir, {{"lc_relay8", 255}});
  const int fd = socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", sim->controlPath().c_str());
  ASSERT_EQ(sim->controlPath(), dir / "tty.ctl");
  ASSERT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  const std::string commands = "set #0 coil 2 1\nget #0 coil 0 3\nnonsense\n";
  ASSERT_EQ(write(fd, commands.data(), commands.size()), static_cast<ssize_t>(commands.size()));
  std::string replies;
  char buf[256];
  while (std::count(replies.begin(), replies.end(), '\n') < 3) {
    pollfd p{fd, POLLIN, 0};
    ASSERT_GT(poll(&p, 1, 5000), 0) << replies;
    const ssize_t n = read(fd, buf, sizeof buf);
    ASSERT_GT(n, 0);
    replies.append(buf, static_cast<size_t>(n));
  }
  EXPECT_EQ(replies, "ok\nok 0 0 1\nerror unknown command 'nonsense' (try help)\n");
  close(fd);
}

TEST(SimPowerCycle, PendingSettingsApplyAndOutputsGoOff) {
  ScratchDir dir;
  auto sim = started(dir, {{"lc_relay8", 255}, {"ld58a08", 1}, {"yespeed_pdu", 2}});
  ASSERT_EQ(sim->command("set 255 coil 0 1 1"), "ok");
  ASSERT_EQ(sim->command("set 255 holding_register 1001 4"), "ok");
  ASSERT_EQ(sim->command("set 1 coil 5 1"), "ok");
  ASSERT_EQ(sim->command("set 1 holding_register 252 3 7 2 1"),
            "ok");  // delay, address 7, 4800, even
  ASSERT_EQ(sim->command("set 2 coil 0 1"), "ok");
  EXPECT_EQ(sim->command("info"),
            "ok #0:lc_relay8:255:9600:N #1:ld58a08:7:9600:N #2:yespeed_pdu:2:9600:N");
  ASSERT_EQ(sim->command("power_cycle"), "ok");
  EXPECT_EQ(sim->command("info"),
            "ok #0:lc_relay8:255:19200:N #1:ld58a08:7:4800:E #2:yespeed_pdu:2:9600:N");
  EXPECT_EQ(sim->command("get 255 coil 0 2"), "ok 0 0");
  EXPECT_EQ(sim->command("get 7 holding_register 128"), "ok 0");
  EXPECT_EQ(sim->command("get 7 holding_register 252"), "ok 3") << "the return delay is stored";
  EXPECT_EQ(sim->command("get 2 coil 0"), "ok 0");
  // SIGHUP's path: the line thread picks the request up.
  ASSERT_EQ(sim->command("set 7 holding_register 254 3"), "ok");
  sim->requestPowerCycle();
  for (int i = 0; i < 200 && sim->command("info").find("7:9600") == std::string::npos; ++i)
    std::this_thread::sleep_for(10ms);
  EXPECT_EQ(sim->command("info"),
            "ok #0:lc_relay8:255:19200:N #1:ld58a08:7:9600:E #2:yespeed_pdu:2:9600:N");
}

TEST(SimStateFile, WhatTheDevicesStoreSurvivesARestart) {
  ScratchDir dir;
  {
    auto sim = started(dir, {{"lc_relay8", 255}, {"ld58a08", 1}, {"yespeed_pdu", 2}});
    ASSERT_EQ(sim->command("set 1 holding_register 253 9 4"), "ok");  // address 9, 19200 pending
    ASSERT_EQ(sim->command("set 2 holding_register 0 2600 1600 700"), "ok");
    ASSERT_EQ(sim->command("set 255 holding_register 1001 2"), "ok");
    const std::string before = fileText(dir / "state.yaml");
    EXPECT_NE(before.find("address: 9"), std::string::npos) << before;
    ASSERT_EQ(sim->command("get 9 coil 0"), "ok 0");
    EXPECT_EQ(fileText(dir / "state.yaml"), before) << "a read changes nothing";
  }
  {
    auto sim = started(dir, {{"lc_relay8", 255}, {"ld58a08", 1}, {"yespeed_pdu", 2}});
    EXPECT_EQ(sim->command("info"),
              "ok #0:lc_relay8:255:9600:N #1:ld58a08:9:9600:N #2:yespeed_pdu:2:9600:N")
        << "baud codes still pending: the restart was no power cycle of the devices' own";
    EXPECT_EQ(sim->command("get 2 holding_register 0 3"), "ok 2600 1600 700");
    ASSERT_EQ(sim->command("power_cycle"), "ok");
  }
  auto sim = started(dir, {{"lc_relay8", 255}, {"ld58a08", 1}, {"yespeed_pdu", 2}});
  EXPECT_EQ(sim->command("info"),
            "ok #0:lc_relay8:255:4800:N #1:ld58a08:9:19200:N #2:yespeed_pdu:2:9600:N");
  // A config with other types at those places keeps its own settings.
  sim.reset();
  auto other = started(dir, {{"yespeed_pdu", 5}, {"ld58a08", 1}});
  EXPECT_EQ(other->command("info"), "ok #0:yespeed_pdu:5:9600:N #1:ld58a08:9:19200:N");
}

TEST(SimStateFile, ABrokenStateFileIsIgnored) {
  ScratchDir dir;
  std::ofstream(dir / "state.yaml") << "devices: [ {type: ld58a08, address: [";
  auto sim = started(dir, {{"ld58a08", 1}});
  EXPECT_EQ(sim->command("info"), "ok #0:ld58a08:1:9600:N");
  std::ofstream(dir / "state.yaml") << "devices: [{type: ld58a08, address: 400, baud: 9600}]";
  sim.reset();
  sim = started(dir, {{"ld58a08", 1}});
  EXPECT_EQ(sim->command("info"), "ok #0:ld58a08:1:9600:N") << "address 400 ignored";
}
