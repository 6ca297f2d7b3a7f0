// The simulated generic device: built from the same YAML as the node's (a template and
// signals), its register block per table, holes answering exception 02, writes applied, inputs
// set from outside, state kept.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "modbus_rtu_driver/sim/sim_generic.h"
#include "test_sim_helpers.h"

using namespace modbus_rtu_driver;
using namespace modbus_rtu_driver::simtest;

namespace {

const char* kConfig = R"(
baud: 9600
devices:
  - type: generic
    address: 7
    template: templates/sdm120.yaml
    signals:
      - {name: setpoint, table: holding_register, address: 100, type: int16, writable: true}
      - {name: counter, table: holding_register, address: 102, type: uint32, writable: true}
      - {name: relay, table: coil, address: 0, writable: true}
    holes:
      - {table: input_register, from: 2, to: 5}
)";

SimulatorConfig load(const std::string& yaml) {
  SimulatorConfig c;
  std::string error;
  EXPECT_TRUE(parseSimulatorConfig(yaml, &c, &error, std::string(REPO_DIR) + "/config")) << error;
  return c;
}

std::string parseError(const std::string& yaml) {
  SimulatorConfig c;
  std::string error;
  EXPECT_FALSE(parseSimulatorConfig(yaml, &c, &error, std::string(REPO_DIR) + "/config"));
  return error;
}

}  // namespace

TEST(SimGeneric, TheSameYamlAsTheNodes) {
  const SimulatorConfig c = load(kConfig);
  ASSERT_EQ(c.devices.size(), 1u);
  EXPECT_EQ(c.devices[0].type, "generic");
  EXPECT_EQ(c.devices[0].generic.map.signals.size(), 13u);  // 10 of the template + 3
  ASSERT_EQ(c.devices[0].generic.holes.size(), 1u);
  EXPECT_EQ(c.devices[0].generic.holes[0].to, 5);
  EXPECT_EQ(parseError("devices: [{type: generic, address: 7, signals: [{name: a}]}]"),
            "devices[0]/signals[0]/table: missing");
  EXPECT_EQ(parseError("devices: [{type: generic, address: 7, holes: [], signals: [{name: a, "
                       "table: coil, address: 0}], colour: red}]"),
            "devices[0]/colour: unknown key (known keys: address, holes, max_gap, max_read, "
            "signals, template, type)");
  EXPECT_EQ(parseError("devices: [{type: lc_relay8, address: 7, holes: []}]"),
            "devices[0]/holes: unknown key (known keys: address, type)");
  EXPECT_EQ(parseError("devices: [{type: generic, address: 7, signals: [{name: a, table: coil, "
                       "address: 0}], holes: [{table: coils, from: 1}]}]"),
            "devices[0]/holes[0]/table: 'coils' is not one of coil, discrete_input, "
            "holding_register, input_register (the table is now named 'coil')");
}

TEST(SimGeneric, TheExampleConfigLoads) {
  SimulatorConfig c;
  std::string error;
  ASSERT_TRUE(
      loadSimulatorConfig(std::string(REPO_DIR) + "/config/simulator_generic.yaml", &c, &error))
      << error;
  ASSERT_EQ(c.devices.size(), 3u);
  EXPECT_EQ(c.devices[0].generic.map.signals.size(), 4u);  // the XY-MD02 template
  EXPECT_EQ(c.devices[2].generic.holes.at(0).from, 0x3002);
}

TEST(SimGeneric, IsBuiltThroughTheRegistryLikeEveryType) {
  const SimulatorConfig c = load(kConfig);
  const auto d = makeSimDevice(c.devices[0], c.factory);
  ASSERT_NE(d, nullptr);
  EXPECT_STREQ(d->type(), "generic");
  EXPECT_EQ(d->address(), 7);
  // The entry's signals and holes came with it.
  const Request read = Request::readHoldingRegisters(7, 102, 2);
  EXPECT_EQ(ask(*d, read), toHex(encodeReply(read, {0, 0})));
  EXPECT_EQ(ask(*d, Request::readInputRegisters(7, 0, 8)), exceptionHex(7, 0x04, 0x02));
  EXPECT_EQ(makeSimDevice({"no_such_type", 7}, c.factory), nullptr);
}

TEST(SimGeneric, BlocksHolesWritesAndInputs) {
  SimulatorConfig c = load(kConfig);
  SimGeneric d(7, {}, c.devices[0].generic);
  // Input registers 0-0x157 answer, except the hole 2-5; a read across it is refused.
  EXPECT_EQ(ask(d, Request::readInputRegisters(7, 0, 2)),
            toHex(encodeReply(Request::readInputRegisters(7, 0, 2), {0, 0})));
  EXPECT_EQ(ask(d, Request::readInputRegisters(7, 0, 8)), exceptionHex(7, 0x04, 0x02));
  EXPECT_EQ(ask(d, Request::readInputRegisters(7, 0x156, 3)), exceptionHex(7, 0x04, 0x02));
  // Inputs from outside (the control socket's set), read back over the bus.
  EXPECT_EQ(d.setDirect(Table::kInputRegister, 6, 0x3FC0, SimClock::now()), 0);
  EXPECT_EQ(get(d, Table::kInputRegister, 6), 0x3FC0);
  EXPECT_EQ(d.setDirect(Table::kInputRegister, 3, 1, SimClock::now()), kIllegalDataAddress);
  // Writes land; an FC16 reaching past the block changes nothing.
  const Request w = Request::writeMultipleRegisters(7, 102, {2, 1});
  EXPECT_EQ(ask(d, w), toHex(encodeReply(w, {})));
  EXPECT_EQ(get(d, Table::kHoldingRegister, 103), 1);
  EXPECT_EQ(ask(d, Request::writeMultipleRegisters(7, 103, {9, 9})), exceptionHex(7, 0x10, 0x02));
  EXPECT_EQ(get(d, Table::kHoldingRegister, 103), 1);
  EXPECT_EQ(ask(d, Request::writeSingleCoil(7, 0, true)),
            toHex(encodeReply(Request::writeSingleCoil(7, 0, true), {})));
  EXPECT_EQ(get(d, Table::kCoil, 0), 1);
  // One value written with the multiple writes (write_function 15 / 16 on the node) lands too.
  const Request fc15 = Request::writeMultipleCoils(7, 0, {false});
  EXPECT_EQ(ask(d, fc15), toHex(encodeReply(fc15, {})));
  EXPECT_EQ(get(d, Table::kCoil, 0), 0);
  const Request fc16 = Request::writeMultipleRegisters(7, 100, {0xFF33});
  EXPECT_EQ(ask(d, fc16), toHex(encodeReply(fc16, {})));
  EXPECT_EQ(get(d, Table::kHoldingRegister, 100), 0xFF33);
  // No discrete inputs configured: that table refuses everything.
  EXPECT_EQ(ask(d, Request::readDiscreteInputs(7, 0, 1)), exceptionHex(7, 0x02, 0x02));
  // State survives a save and load.
  YAML::Node state;
  d.saveState(state);
  SimGeneric again(7, {}, c.devices[0].generic);
  again.loadState(state, SimClock::now());
  EXPECT_EQ(get(again, Table::kHoldingRegister, 102), 2);
  EXPECT_EQ(get(again, Table::kInputRegister, 6), 0x3FC0);
}

// Issue 24: max_read makes the simulated device answer longer reads with exception 03 (as
// Eastron meters do); the protocol's own limit still holds above it.
TEST(SimGeneric, MaxReadRefusesLongerReadsWithException03) {
  SimulatorConfig c = load(R"(
devices:
  - type: generic
    address: 7
    max_read: 4
    signals:
      - {name: a, table: input_register, address: 0, type: float32}
      - {name: b, table: input_register, address: 6, type: float32}
      - {name: c, table: coil, address: 0}
      - {name: d, table: coil, address: 9}
)");
  ASSERT_EQ(c.devices.size(), 1u);
  EXPECT_EQ(c.devices[0].generic.max_read, 4);
  SimGeneric d(7, {}, c.devices[0].generic);
  const Request four = Request::readInputRegisters(7, 0, 4);
  EXPECT_EQ(ask(d, four), toHex(encodeReply(four, {0, 0, 0, 0})));
  EXPECT_EQ(ask(d, Request::readInputRegisters(7, 0, 8)), exceptionHex(7, 0x04, 0x03));
  EXPECT_EQ(ask(d, Request::readCoils(7, 0, 10)), exceptionHex(7, 0x01, 0x03));
  EXPECT_EQ(parseError("devices: [{type: generic, address: 7, max_read: 0, signals: [{name: a, "
                       "table: coil, address: 0}]}]"),
            "devices[0]/max_read: 0 is outside 1-2000");
}
