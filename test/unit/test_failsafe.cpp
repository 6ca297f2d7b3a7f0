// The fail-safe configuration (ROS-free): its rules, the heartbeat watchdog on a manual clock,
// and what a safe write sends (scripted transport, byte exact). What each channel should show is
// in test_channel_intents.cpp.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "bus_config_fixtures.h"
#include "modbus_rtu_driver/core/bus/watchdog.h"
#include "modbus_rtu_driver/devices/failsafe.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/devices/output_batch.h"
#include "modbus_rtu_driver/failsafe/channel_intents.h"
#include "modbus_rtu_driver/node_config/bus_config.h"
#include "scripted_transport.h"

using namespace modbus_rtu_driver;
using configtest::errorOf;
using namespace std::chrono_literals;

namespace {

const char* kBus = R"(
port: /dev/null
heartbeat: {topic: /robot/alive, timeout: 0.5}
devices:
  relays:
    type: lc_relay8
    address: 255
    outputs: [pump, valve, lamp, fan, out4, out5, out6, out7]
    safe_state: {pump: off, valve: off, lamp: on}
    command_timeout: {pump: 2.0}
    on_restart: restore
    on_start: safe
  pdu: {type: yespeed_pdu, address: 2, safe_state: off, heartbeat: {topic: pdu_alive, timeout: 1}}
)";

std::string device(const std::string& settings) {
  return "devices: {relays: {type: lc_relay8, address: 255, " + settings + "}}";
}

}  // namespace

TEST(FailsafeConfig, ParsesPerChannelAndForAll) {
  BusConfig c;
  std::string error;
  ASSERT_TRUE(parseBusConfig(YAML::Load(kBus), &c, &error)) << error;
  EXPECT_EQ(c.heartbeat_topic, "/robot/alive");
  EXPECT_DOUBLE_EQ(c.heartbeat_timeout, 0.5);
  const FailsafeConfig& r =
      c.devices[0].name == "relays" ? c.devices[0].failsafe : c.devices[1].failsafe;
  const FailsafeConfig& p =
      c.devices[0].name == "pdu" ? c.devices[0].failsafe : c.devices[1].failsafe;
  EXPECT_EQ(r.safeStateOf(0), SafeState::kOff);
  EXPECT_EQ(r.safeStateOf(1), SafeState::kOff);
  EXPECT_EQ(r.safeStateOf(2), SafeState::kOn);
  EXPECT_EQ(r.safeStateOf(3), SafeState::kLeave);
  EXPECT_DOUBLE_EQ(r.commandTimeoutOf(0), 2.0);
  EXPECT_DOUBLE_EQ(r.commandTimeoutOf(1), 0.0);
  EXPECT_EQ(r.on_restart, OnRestart::kRestore);
  EXPECT_TRUE(r.on_start_safe);
  for (size_t i = 0; i < 8; ++i) EXPECT_EQ(p.safeStateOf(i), SafeState::kOff) << i;
  EXPECT_EQ(p.heartbeat_topic, "pdu_alive");
  EXPECT_EQ(p.on_restart, OnRestart::kLeave);  // the defaults change nothing
  EXPECT_FALSE(p.on_start_safe);
}

// on_start: leave is on_restart's word for "as the node finds them"; keep, the word before it,
// is still taken in this release, with a deprecation the node logs (docs/releases.md).
TEST(FailsafeConfig, OnStartLeaveAndTheDeprecatedKeep) {
  BusConfig leave;
  std::string error;
  ASSERT_TRUE(parseBusConfig(YAML::Load(device("on_start: leave")), &leave, &error)) << error;
  EXPECT_FALSE(leave.devices[0].failsafe.on_start_safe);
  EXPECT_TRUE(leave.deprecated.empty());
  BusConfig keep;
  ASSERT_TRUE(parseBusConfig(YAML::Load(device("on_start: keep")), &keep, &error)) << error;
  EXPECT_FALSE(keep.devices[0].failsafe.on_start_safe);
  EXPECT_EQ(keep.deprecated,
            std::vector<std::string>{"devices/relays/on_start: 'keep' is deprecated, use 'leave' "
                                     "(the same)"});
}

// rosparam turns a bare off/on into booleans; both spellings mean the same.
TEST(FailsafeConfig, BooleansFromRosparamAreOffAndOn) {
  BusConfig c;
  std::string error;
  ASSERT_TRUE(
      parseBusConfig(YAML::Load(device("safe_state: {out0: false, out1: true}")), &c, &error))
      << error;
  EXPECT_EQ(c.devices[0].failsafe.safeStateOf(0), SafeState::kOff);
  EXPECT_EQ(c.devices[0].failsafe.safeStateOf(1), SafeState::kOn);
}

TEST(FailsafeConfig, BadValuesAreRefusedWithTheKeyNamed) {
  EXPECT_EQ(errorOf(device("safe_state: maybe")),
            "devices/relays/safe_state: 'maybe' is not one of on, off, hold (on/off also as "
            "true/false, yes/no, 1/0)");
  EXPECT_EQ(errorOf(device("safe_state: {pumpx: off}")),
            "devices/relays/safe_state/pumpx: no output channel of that name (outputs: out0, "
            "out1, out2, out3, out4, out5, out6, out7)");
  EXPECT_EQ(errorOf(device("safe_state: [off]")),
            "devices/relays/safe_state: a list is neither one value for all channels nor a map "
            "by name");
  EXPECT_EQ(errorOf(device("command_timeout: 1.0")),
            "devices/relays/command_timeout/out0: needs a safe_state of off or on for that "
            "channel (it is hold)");
  EXPECT_NE(errorOf(device("safe_state: off, command_timeout: 0.01")).find("outside 0.05-3600"),
            std::string::npos);
  EXPECT_EQ(errorOf(device("on_restart: reboot")),
            "devices/relays/on_restart: 'reboot' is not one of restore, safe, leave");
  EXPECT_EQ(errorOf(device("on_start: off")),
            "devices/relays/on_start: 'off' is not safe or leave");
  EXPECT_EQ(
      errorOf(device("heartbeat: {topic: x}")),
      "devices/relays/heartbeat/timeout: missing (s without a message before the safe state)");
  EXPECT_EQ(errorOf(device("heartbeat: {topic: x, timeout: 1, rate: 2}"))
                .rfind("devices/relays/heartbeat/rate: unknown key", 0),
            0u);
  EXPECT_NE(errorOf("heartbeat: {topic: x, timeout: 0}\n" + device("safe_state: off"))
                .find("heartbeat/timeout: 0 s is outside 0.05-3600 s"),
            std::string::npos);
  EXPECT_NE(errorOf("shutdown_timeout: 100\n" + device("safe_state: off")).find("shutdown_timeout"),
            std::string::npos);
}

TEST(ChannelIntents, SafeTargetsLeaveHoldChannelsAlone) {
  FailsafeConfig c;
  c.safe_state = {SafeState::kOff, SafeState::kLeave, SafeState::kOn};
  ChannelIntents t(c, 3);
  const OutputTargets s = t.safeTargets();
  EXPECT_EQ(s.channels, (std::vector<uint8_t>{0, 2}));
  EXPECT_EQ(s.states, (std::vector<bool>{false, true}));
}

TEST(Watchdog, ExpiresOnceAndIsReArmedByAFeed) {
  ManualClock clock;
  Watchdog w(0.5, clock);
  clock.advance(499ms);
  EXPECT_FALSE(w.expired());  // armed from the start
  clock.advance(1ms);
  EXPECT_TRUE(w.expired());
  EXPECT_TRUE(w.tripped());
  clock.advance(10s);
  EXPECT_FALSE(w.expired());  // once
  w.feed();
  EXPECT_FALSE(w.tripped());
  clock.advance(400ms);
  w.feed();
  clock.advance(400ms);
  EXPECT_FALSE(w.expired());
  clock.advance(100ms);
  EXPECT_TRUE(w.expired());
}

// What the safe write of an LC board sends: pump and valve off, lamp on (FC15 over 0-2).
TEST(ChannelIntents, TheSafeWriteIsOneFrame) {
  DeviceConfig dc;
  dc.name = "relays";
  dc.type = "lc_relay8";
  dc.address = 255;
  LcRelay8 board(dc);
  FailsafeConfig c;
  c.safe_state = {SafeState::kOff, SafeState::kOff, SafeState::kOn};
  ChannelIntents t(c, 8);
  const OutputTargets s = t.safeTargets();
  ScriptedTransport bus;
  bus.expectEcho(toHex(encodeRequest(Request::writeMultipleCoils(255, 0, {false, false, true}))));
  EXPECT_TRUE(OutputBatch::write(board, bus, s.channels, s.states).ok());
  EXPECT_TRUE(bus.usedUp());
  EXPECT_EQ(bus.mismatches(), "");
}

// Issue #24 item 2: a safe write is a command like any other; a restore writes it again.
// Issue #24 item 1: while a lasting trigger holds a channel safe, a restore keeps it safe, even
// when the safe write itself never got through; a user's command ends the hold.
// Issue #24 item 3: a write the node carried for a share client, confirmed by the reply, is
// taken as a command at the next poll, not as a power cycle; a restore writes it again.
// Found by the scenario test (seed 354232319): a share client's FC05 that sets an output to the
// state it already had changes nothing a poll can see, yet it is a command a restore writes again.
TEST(Device, OutputsWrittenByACoilWrite) {
  DeviceConfig board;
  board.address = 255;
  const LcRelay8 relays(board);
  OutputTargets set =
      relays.outputsWrittenBy(Request::writeMultipleCoils(255, 6, {true, false, true}));
  EXPECT_EQ(set.channels, (std::vector<uint8_t>{6, 7}));  // coil 8 is not an output
  EXPECT_EQ(set.states, (std::vector<bool>{true, false}));
  EXPECT_TRUE(relays.outputsWrittenBy(Request::writeSingleRegister(255, 2, 1)).empty());
  set = relays.outputsWrittenBy(Request::writeSingleCoil(255, 0, false));
  EXPECT_EQ(set.channels, (std::vector<uint8_t>{0}));
  EXPECT_EQ(set.states, (std::vector<bool>{false}));
}

// Found by the scenario test (seed 354232319): a device that comes back while a safe write is
// pending gets the restore of its other channels too, the pending safe states over it.
// Found by the scenario test (seed 1268616613): a share client's write ran between the
// transactions of a poll (they go ahead of each one), so the coils that poll had read were
// older than the write. Taken as the client's command, they made the next poll look like a
// restart, and the restore undid the client's write.