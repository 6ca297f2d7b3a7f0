// The simulated Yespeed PDU: relays, telemetry that moves and follows the outlets, the limit
// rules of the manual, pins from outside, power cycle and state.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>

#include "modbus_rtu_driver/sim/sim_yespeed_pdu.h"
#include "test_sim_helpers.h"

using namespace modbus_rtu_driver;
using namespace modbus_rtu_driver::simtest;

namespace {

struct Telemetry {
  double temperature, humidity, voltage, current, power;
};

Telemetry telemetry(SimDevice& d, SimClock::time_point now) {
  std::vector<uint16_t> r;
  for (uint16_t a = 0; a < 5; ++a) r.push_back(get(d, Table::kInputRegister, a, now));
  return {static_cast<int16_t>(r[0]) / 10.0, r[1] / 10.0, r[2] / 10.0, r[3] / 100.0,
          static_cast<double>(r[4])};
}

std::string refused(SimDevice& d, uint16_t address, const std::vector<uint16_t>& values) {
  return ask(d, Request::writeMultipleRegisters(1, address, values)) ==
                 exceptionHex(1, 0x10, kIllegalDataValue)
             ? "refused"
             : "accepted";
}

}  // namespace

TEST(SimYespeedPdu, LimitRulesOfTheManual) {
  SimYespeedPdu d(1, {});
  EXPECT_EQ(ask(d, "01 03 00 00 00 03 05 CB"), "01 03 06 09 C4 07 D0 06 40 D2 E0");
  EXPECT_EQ(refused(d, 0, {1800}), "refused") << "over-voltage > 180.0 V";
  EXPECT_EQ(refused(d, 1, {2800}), "refused") << "under-voltage < 280.0 V";
  EXPECT_EQ(refused(d, 2, {500}), "refused") << "current > 5.00 A";
  EXPECT_EQ(refused(d, 2, {2000}), "refused") << "current < 20.00 A";
  EXPECT_EQ(refused(d, 1, {2500}), "refused") << "under-voltage below over-voltage";
  EXPECT_EQ(refused(d, 2, {501}), "accepted");
  EXPECT_EQ(refused(d, 2, {1999}), "accepted");
  EXPECT_EQ(refused(d, 1, {2499}), "accepted");
  EXPECT_EQ(refused(d, 0, {1801, 1800}), "accepted") << "over-voltage at its lower edge";
  EXPECT_EQ(refused(d, 0, {2799, 2700}), "accepted");
  // FC16 is checked as a whole: 190/185 V is fine together, not one by one from 279.9/270.0.
  EXPECT_EQ(refused(d, 0, {1900}), "refused");
  EXPECT_EQ(refused(d, 0, {1900, 1850}), "accepted");
  EXPECT_EQ(refused(d, 0, {2600, 2700, 700}), "refused");
  EXPECT_EQ(ask(d, Request::readHoldingRegisters(1, 0, 3)),
            toHex(encodeReply(Request::readHoldingRegisters(1, 0, 3), {1900, 1850, 1999})))
      << "a refused write changed nothing";
  EXPECT_EQ(
      ask(d, "01 10 00 00 00 03 06 0A 28 06 40 02 BC 87 A1"),
      toHex(encodeReply(*decodeRequest(hex("01 10 00 00 00 03 06 0A 28 06 40 02 BC 87 A1")), {})));
  EXPECT_EQ(ask(d, Request::writeMultipleRegisters(1, 1, {2000, 700, 1})),
            exceptionHex(1, 0x10, kIllegalDataAddress));
  EXPECT_EQ(ask(d, Request::readHoldingRegisters(1, 3, 1)),
            exceptionHex(1, 0x03, kIllegalDataAddress));
}

TEST(SimYespeedPdu, TelemetryIsPlausibleAndConsistent) {
  SimYespeedPdu d(1, {});
  const auto t0 = SimClock::now();
  for (int i = 0; i < 40; ++i) {
    const Telemetry t = telemetry(d, t0 + std::chrono::seconds(37 * i));
    EXPECT_GT(t.temperature, 15.0);
    EXPECT_LT(t.temperature, 30.0);
    EXPECT_GT(t.humidity, 40.0);
    EXPECT_LT(t.humidity, 70.0);
    EXPECT_GT(t.voltage, 210.0);
    EXPECT_LT(t.voltage, 230.0);
    EXPECT_LT(t.current, 0.2) << "only the PDU itself draws";
    EXPECT_NEAR(t.power, t.voltage * t.current * 0.98, 0.6);
  }
}

TEST(SimYespeedPdu, CurrentFollowsTheOutletsSwitchedOn) {
  SimYespeedPdu d(1, {});
  const auto t0 = SimClock::now();
  double last = telemetry(d, t0).current;
  for (uint16_t n = 1; n <= 8; ++n) {
    ASSERT_EQ(d.write(Table::kCoil, static_cast<uint16_t>(n - 1), {1}, t0), 0);
    const Telemetry t = telemetry(d, t0);
    EXPECT_GT(t.current, last + 0.4) << n << " outlets on";
    EXPECT_NEAR(t.power, t.voltage * t.current * 0.98, 2.0) << n;
    last = t.current;
  }
  EXPECT_GT(last, 5.0);
  EXPECT_LT(last, 10.0);
  EXPECT_EQ(ask(d, "01 0F 00 00 00 08 01 00 FE 95"), "01 0F 00 00 00 08 54 0D");
  EXPECT_LT(telemetry(d, t0).current, 0.2);
}

TEST(SimYespeedPdu, ValuesMoveOverTimeWithNoise) {
  SimYespeedPdu d(1, {});
  ASSERT_EQ(d.write(Table::kCoil, 0, {1, 1, 1}, SimClock::now()), 0);
  const auto t0 = SimClock::now();
  std::set<uint16_t> volts, amps;
  for (int i = 0; i < 30; ++i) {
    const auto t = t0 + std::chrono::milliseconds(600 * i);
    volts.insert(get(d, Table::kInputRegister, 2, t));
    amps.insert(get(d, Table::kInputRegister, 3, t));
  }
  EXPECT_GT(volts.size(), 5u);
  EXPECT_GE(amps.size(), 3u);
  // Within one measurement period the values hold still.
  const auto t = t0 + 100s;
  EXPECT_EQ(get(d, Table::kInputRegister, 2, t), get(d, Table::kInputRegister, 2, t + 100ms));
}

TEST(SimYespeedPdu, PinsFromOutsideUntilPowerCycle) {
  SimYespeedPdu d(1, {});
  const auto now = SimClock::now();
  ASSERT_EQ(d.setDirect(Table::kInputRegister, 0, static_cast<uint16_t>(-55), now), 0);
  ASSERT_EQ(d.setDirect(Table::kInputRegister, 2, 2305, now), 0);
  ASSERT_EQ(d.setDirect(Table::kInputRegister, 3, 1000, now), 0);
  const Telemetry t = telemetry(d, now + 1h);
  EXPECT_DOUBLE_EQ(t.temperature, -5.5);
  EXPECT_DOUBLE_EQ(t.voltage, 230.5);
  EXPECT_DOUBLE_EQ(t.power, std::round(230.5 * 10.0 * 0.98)) << "power from the pinned values";
  EXPECT_EQ(d.setDirect(Table::kInputRegister, 5, 1, now), kIllegalDataAddress);
  ASSERT_EQ(d.write(Table::kCoil, 2, {1}, now), 0);
  d.powerCycle(now);
  EXPECT_EQ(get(d, Table::kCoil, 2), 0) << "relays off after power-on";
  EXPECT_GT(telemetry(d, now).temperature, 15.0) << "pins gone";
}

TEST(SimYespeedPdu, UnsupportedTablesAndAddresses) {
  SimYespeedPdu d(1, {});
  EXPECT_EQ(ask(d, Request::readDiscreteInputs(1, 0, 1)), exceptionHex(1, 0x02, kIllegalFunction));
  EXPECT_EQ(ask(d, Request::readInputRegisters(1, 4, 2)),
            exceptionHex(1, 0x04, kIllegalDataAddress));
  EXPECT_EQ(ask(d, Request::readCoils(1, 0, 9)), exceptionHex(1, 0x01, kIllegalDataAddress));
  Bytes too_many{1, 0x04, 0x00, 0x00, 0x00, 126};
  appendCrc(too_many);
  EXPECT_EQ(ask(d, toHex(too_many)), exceptionHex(1, 0x04, kIllegalDataValue));
}

TEST(SimYespeedPdu, StateKeepsTheLimits) {
  SimYespeedPdu d(1, {});
  ASSERT_EQ(d.write(Table::kHoldingRegister, 0, {2600, 1600, 700}, SimClock::now()), 0);
  YAML::Node node;
  d.saveState(node);
  SimYespeedPdu e(1, {});
  e.loadState(YAML::Load(YAML::Dump(node)), SimClock::now());
  EXPECT_EQ(get(e, Table::kHoldingRegister, 0), 2600);
  EXPECT_EQ(get(e, Table::kHoldingRegister, 1), 1600);
  EXPECT_EQ(get(e, Table::kHoldingRegister, 2), 700);
  node["limits"][0] = 100;  // breaks the rules: ignored
  SimYespeedPdu f(1, {});
  f.loadState(YAML::Load(YAML::Dump(node)), SimClock::now());
  EXPECT_EQ(get(f, Table::kHoldingRegister, 0), 2500);
}
