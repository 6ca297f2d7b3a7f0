// The generic device against a scripted transport (byte exact through the framing): merged
// reads within max_gap and the protocol's limits, splitting after exception 02 (remembered),
// poll groups by rate, writes checked before the bus and confirmed.
#include <gtest/gtest.h>

#include <cmath>

#include "device_fixtures.h"
#include "modbus_rtu_driver/devices/generic_device.h"
#include "modbus_rtu_driver/devices/output_batch.h"
#include "modbus_rtu_driver/devices/registry.h"

using namespace modbus_rtu_driver;

namespace {

SignalConfig sig(const std::string& name, Table table, uint16_t address,
                 SignalType type = SignalType::kUint16) {
  SignalConfig s;
  s.name = name;
  s.table = table;
  s.address = address;
  s.type = isBitTable(table) ? SignalType::kBool : type;
  return s;
}

DeviceConfig generic(std::vector<SignalConfig> signals, int max_gap = 8) {
  DeviceConfig c;
  c.name = "meter";
  c.type = "generic";
  c.address = 5;
  c.poll_rate = 1.0;
  c.generic.signals = std::move(signals);
  c.generic.max_gap = max_gap;
  return c;
}

void expectRead(ScriptedTransport& bus, const Request& r, const std::vector<uint16_t>& values) {
  bus.expect(toHex(encodeRequest(r)), toHex(encodeReply(r, values)));
}

void expectRefused(ScriptedTransport& bus, const Request& r, uint8_t code) {
  bus.expect(toHex(encodeRequest(r)),
             toHex(encodeException(r.slave, static_cast<uint8_t>(r.function), code)));
}

const auto kH = Table::kHoldingRegister;
const auto kI = Table::kInputRegister;

}  // namespace

TEST(ReadPlanner, MergesWithinMaxGapByTable) {
  ReadPlanner p({sig("a", kH, 0), sig("b", kH, 3, SignalType::kUint32), sig("c", kH, 14),
                 sig("d", kI, 4), sig("e", Table::kCoil, 0), sig("f", Table::kCoil, 9)},
                8);
  const auto spans = p.plan({0, 1, 2, 3, 4, 5});
  ASSERT_EQ(spans.size(), 4u);
  EXPECT_EQ(spans[0].table, Table::kCoil);  // coils 0 and 9: 8 bits apart, merged
  EXPECT_EQ(spans[0].address, 0);
  EXPECT_EQ(spans[0].count, 10);
  EXPECT_EQ(spans[1].table, kH);  // a (0) and b (3-4): gap 2
  EXPECT_EQ(spans[1].count, 5);
  EXPECT_EQ(spans[1].signals, (std::vector<size_t>{0, 1}));
  EXPECT_EQ(spans[2].address, 14);  // c: 9 registers after b, beyond max_gap 8
  EXPECT_EQ(spans[3].table, kI);
  // max_gap 0: only adjacent signals share a request.
  ReadPlanner adjacent({sig("a", kH, 0), sig("b", kH, 1), sig("c", kH, 3)}, 0);
  EXPECT_EQ(adjacent.plan({0, 1, 2}).size(), 2u);
}

TEST(ReadPlanner, KeepsTheProtocolLimits) {
  // 125 registers at most: signals at 0 and 124 fit one request, 0 and 125 do not.
  std::vector<SignalConfig> regs;
  for (uint16_t a = 0; a <= 126; ++a) regs.push_back(sig("r" + std::to_string(a), kH, a));
  ReadPlanner p(regs, 8);
  std::vector<size_t> all;
  for (size_t i = 0; i < regs.size(); ++i) all.push_back(i);
  const auto spans = p.plan(all);
  ASSERT_EQ(spans.size(), 2u);
  EXPECT_EQ(spans[0].count, kMaxReadRegisters);
  EXPECT_EQ(spans[1].address, 125);
  // 2000 bits.
  ReadPlanner bits({sig("a", Table::kDiscreteInput, 0), sig("b", Table::kDiscreteInput, 1999),
                    sig("c", Table::kDiscreteInput, 2000)},
                   123);
  EXPECT_EQ(bits.plan({0, 1}).size(), 2u);  // 1998 bits apart: beyond max_gap
  std::vector<SignalConfig> many;
  for (uint16_t a = 0; a < 2001; a += 100)
    many.push_back(sig("b" + std::to_string(a), Table::kDiscreteInput, a));
  ReadPlanner wide(many, 123);
  std::vector<size_t> idx;
  for (size_t i = 0; i < many.size(); ++i) idx.push_back(i);
  const auto bit_spans = wide.plan(idx);
  ASSERT_EQ(bit_spans.size(), 2u);
  EXPECT_EQ(bit_spans[0].count, 1901);  // 0..1900; 2000 would make 2001 bits
  EXPECT_EQ(bit_spans[1].address, 2000);
}

TEST(GenericDevice, PollDecodesAMergedRead) {
  auto t = sig("temperature", kI, 1, SignalType::kInt16);
  t.scale = 0.1;
  auto v = sig("voltage", kI, 4, SignalType::kFloat32);
  auto big = sig("count", kI, 6, SignalType::kUint32);
  big.word_order = WordOrder::kLittle;
  big.offset = -1;
  GenericDevice d(generic({t, v, big}));
  ScriptedTransport bus;
  // 1-7 in one FC04: -20.5 C, 2 unread, 230.0 V, 65538 - 1.
  expectRead(bus, Request::readInputRegisters(5, 1, 7), {0xFF33, 0, 0, 0x4366, 0, 2, 1});
  const Result r = d.poll(bus);
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(d.states()[0].value, -20.5, 1e-9);
  EXPECT_EQ(d.states()[1].value, 230.0);
  EXPECT_EQ(d.states()[2].value, 65537.0);
  EXPECT_TRUE(d.states()[0].valid && d.states()[1].valid && d.states()[2].valid);
  EXPECT_SCRIPT_DONE(bus);
}

TEST(GenericDevice, RefusedMergedSpanIsSplitAndTheSplitRemembered) {
  GenericDevice d(generic({sig("a", kH, 0), sig("b", kH, 2), sig("c", kH, 8)}));
  ScriptedTransport bus;
  // 0-8 refused (a hole at 3-7): split at the widest gap, between b and c.
  expectRefused(bus, Request::readHoldingRegisters(5, 0, 9), kIllegalDataAddress);
  expectRead(bus, Request::readHoldingRegisters(5, 0, 3), {10, 0, 12});
  expectRead(bus, Request::readHoldingRegisters(5, 8, 1), {18});
  const Result r = d.poll(bus);
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(d.states()[0].value, 10);
  EXPECT_EQ(d.states()[1].value, 12);
  EXPECT_EQ(d.states()[2].value, 18);
  ASSERT_EQ(d.splits().size(), 1u);
  EXPECT_NE(d.splits()[0].find("holding_register 0-8 (a, b, c) refused (exception 02)"),
            std::string::npos)
      << d.splits()[0];
  // The next poll reads the two parts straight away.
  expectRead(bus, Request::readHoldingRegisters(5, 0, 3), {11, 0, 13});
  expectRead(bus, Request::readHoldingRegisters(5, 8, 1), {19});
  EXPECT_TRUE(d.poll(bus).ok());
  EXPECT_EQ(d.states()[2].value, 19);
  EXPECT_EQ(d.splits().size(), 1u);
  EXPECT_SCRIPT_DONE(bus);
}

TEST(GenericDevice, ASignalRefusedAloneTurnsInvalidAndThePollSaysWhich) {
  GenericDevice d(generic({sig("a", kH, 0), sig("b", kH, 1)}));
  ScriptedTransport bus;
  expectRefused(bus, Request::readHoldingRegisters(5, 0, 2), kIllegalDataAddress);
  expectRead(bus, Request::readHoldingRegisters(5, 0, 1), {7});
  expectRefused(bus, Request::readHoldingRegisters(5, 1, 1), kIllegalDataAddress);
  const Result r = d.poll(bus);
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.exception_code, kIllegalDataAddress);
  EXPECT_NE(r.message.find("holding_register 1-1 (b)"), std::string::npos) << r.message;
  EXPECT_TRUE(d.states()[0].valid);
  EXPECT_FALSE(d.states()[1].valid);
  EXPECT_SCRIPT_DONE(bus);
}

TEST(GenericDevice, SilenceStopsThePollAndInvalidatesTheRest) {
  GenericDevice d(generic({sig("a", kH, 0), sig("b", kI, 0)}));
  ScriptedTransport bus;
  bus.expect(toHex(encodeRequest(Request::readHoldingRegisters(5, 0, 1))));  // timeout
  const Result r = d.poll(bus);
  EXPECT_EQ(r.error, ErrorKind::kTimeout);
  EXPECT_FALSE(d.states()[0].valid);
  EXPECT_FALSE(d.states()[1].valid);
  EXPECT_SCRIPT_DONE(bus);  // the input register was not asked
}

TEST(GenericDevice, SignalsWithTheirOwnRateFormGroups) {
  auto fast = sig("current", kI, 6, SignalType::kFloat32);
  fast.poll_rate = 20.0;
  auto slow = sig("energy", kI, 0x48, SignalType::kFloat32);
  slow.poll_rate = 0.2;
  GenericDevice d(generic({sig("voltage", kI, 0, SignalType::kFloat32), fast, slow}));
  ASSERT_EQ(d.groups().size(), 3u);
  EXPECT_EQ(d.groups()[0].rate, 1.0);
  EXPECT_EQ(d.groups()[0].signals, std::vector<size_t>{0});
  EXPECT_EQ(d.groups()[1].rate, 20.0);
  EXPECT_EQ(d.groups()[1].signals, std::vector<size_t>{1});
  ScriptedTransport bus;
  expectRead(bus, Request::readInputRegisters(5, 6, 2), {0x3FC0, 0});  // 1.5 A alone
  EXPECT_TRUE(d.pollGroup(bus, 1).ok());
  EXPECT_EQ(d.states()[1].value, 1.5);
  EXPECT_FALSE(d.states()[0].known);
  EXPECT_SCRIPT_DONE(bus);
}

TEST(GenericDevice, WritesAreCheckedBeforeTheBus) {
  auto sp = sig("setpoint", kH, 10, SignalType::kInt16);
  sp.writable = true;
  sp.scale = 0.1;
  sp.min = -50;
  sp.max = 50;
  auto raw = sig("raw", kH, 11, SignalType::kUint16);
  raw.writable = true;
  auto ro = sig("ro", kI, 0);
  GenericDevice d(generic({sp, raw, ro}));
  ScriptedTransport bus;  // nothing may be sent
  EXPECT_EQ(d.writeSignal(bus, 0, 50.1).message, "setpoint: 50.1 is outside -50 to 50");
  EXPECT_EQ(d.writeSignal(bus, 1, 65536).message,
            "raw: 65536 is raw 65536, outside what uint16 holds (0 to 65535)");
  EXPECT_EQ(d.writeSignal(bus, 1, -1).error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(d.writeSignal(bus, 1, std::nan("")).error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(d.writeSignal(bus, 2, 1).message, "ro: not writable");
  EXPECT_EQ(bus.executed(), 0);
}

TEST(GenericDevice, WritesUseFc06Fc16Fc05AndTheEchoConfirms) {
  auto sp = sig("setpoint", kH, 10, SignalType::kInt16);
  sp.writable = true;
  sp.scale = 0.1;
  auto f = sig("limit", kH, 20, SignalType::kFloat32);
  f.writable = true;
  f.word_order = WordOrder::kLittle;
  auto relay = sig("relay", Table::kCoil, 3);
  relay.writable = true;
  GenericDevice d(generic({sp, f, relay}));
  ScriptedTransport bus;
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleRegister(5, 10, 0xFF33))));  // -20.5
  bus.expectEcho(
      toHex(encodeRequest(Request::writeMultipleRegisters(5, 20, {0x0000, 0x4366}))));  // 230
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleCoil(5, 3, true))));
  EXPECT_TRUE(d.writeSignal(bus, 0, -20.5).ok());
  EXPECT_NEAR(d.states()[0].value, -20.5, 1e-9);
  EXPECT_TRUE(d.writeSignal(bus, 1, 230.0).ok());
  EXPECT_EQ(d.states()[1].value, 230.0);
  EXPECT_TRUE(d.writeSignal(bus, 2, 1).ok());
  EXPECT_EQ(d.states()[2].value, 1.0);
  EXPECT_SCRIPT_DONE(bus);
}

TEST(GenericDevice, ALostReplyIsConfirmedOrDeniedByReadingBack) {
  auto sp = sig("setpoint", kH, 10, SignalType::kUint32);
  sp.writable = true;
  GenericDevice d(generic({sp}));
  ScriptedTransport bus;
  const Request w = Request::writeMultipleRegisters(5, 10, {0x0001, 0x0002});
  bus.expect(toHex(encodeRequest(w)));  // reply lost
  expectRead(bus, Request::readHoldingRegisters(5, 10, 2), {0x0001, 0x0002});
  Result r = d.writeSignal(bus, 0, 65538);
  EXPECT_TRUE(r.ok());
  EXPECT_NE(r.message.find("confirmed by reading setpoint back"), std::string::npos);
  bus.expect(toHex(encodeRequest(w)));  // lost again, and not done this time
  expectRead(bus, Request::readHoldingRegisters(5, 10, 2), {0, 7});
  r = d.writeSignal(bus, 0, 65538);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.message.find("read back: not done (setpoint is 7)"), std::string::npos) << r.message;
  // A refusal is not read back: the device said no.
  expectRefused(bus, w, kIllegalDataValue);
  EXPECT_EQ(d.writeSignal(bus, 0, 65538).error, ErrorKind::kException);
  EXPECT_SCRIPT_DONE(bus);
}

namespace {

// A device that only implements the multiple writes: setpoint (int16, x0.1, register 10) with
// FC16 and relay (coil 3) with FC15.
DeviceConfig multipleWritesOnly() {
  auto sp = sig("setpoint", kH, 10, SignalType::kInt16);
  sp.writable = true;
  sp.scale = 0.1;
  sp.write_function = 16;
  auto relay = sig("relay", Table::kCoil, 3);
  relay.writable = true;
  relay.write_function = 15;
  return generic({sp, relay});
}

}  // namespace

// One value with FC16 / FC15, bytes as on the wire (CRCs worked out by hand, not by frame.cpp).
TEST(GenericDevice, WriteFunction16And15SendOneValueAsMultipleWrites) {
  GenericDevice d(multipleWritesOnly());
  ScriptedTransport bus;
  // FC16: slave 5, register 10, 1 register, 2 bytes, 0xFF33 (-20.5 at scale 0.1); echo.
  bus.expect("05 10 00 0A 00 01 02 FF 33 95 DF", "05 10 00 0A 00 01 20 4F");
  // FC15: slave 5, coil 3, 1 coil, 1 byte, bit 0 set; echo.
  bus.expect("05 0F 00 03 00 01 01 01 AA A4", "05 0F 00 03 00 01 65 8F");
  const Result r = d.writeSignal(bus, 0, -20.5);
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(d.states()[0].value, -20.5, 1e-9);
  EXPECT_TRUE(d.writeSignal(bus, 1, 1).ok());
  EXPECT_EQ(d.states()[1].value, 1.0);
  EXPECT_SCRIPT_DONE(bus);
}

TEST(GenericDevice, ALostReplyToFc16OrFc15IsReadBack) {
  GenericDevice d(multipleWritesOnly());
  ScriptedTransport bus;
  bus.expect("05 10 00 0A 00 01 02 FF 33 95 DF");                 // reply lost
  bus.expect("05 03 00 0A 00 01 A5 8C", "05 03 02 FF 33 48 61");  // FC03 1 register: done
  Result r = d.writeSignal(bus, 0, -20.5);
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_NE(r.message.find("confirmed by reading setpoint back"), std::string::npos);
  bus.expect("05 0F 00 03 00 01 01 01 AA A4");                 // reply lost
  bus.expect("05 01 00 03 00 01 0C 4E", "05 01 01 00 50 B8");  // FC01: coil 3 is off
  r = d.writeSignal(bus, 1, 1);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.message.find("read back: not done (relay is 0)"), std::string::npos) << r.message;
  EXPECT_SCRIPT_DONE(bus);
}

TEST(GenericDevice, AWriteFunctionThatCannotWriteTheSignalSendsNothing) {
  // The YAML refuses these; a config built in code is checked again before the bus.
  auto wide = sig("wide", kH, 0, SignalType::kUint32);
  wide.writable = true;
  wide.write_function = 6;
  auto coil = sig("coil", Table::kCoil, 0);
  coil.writable = true;
  coil.write_function = 16;
  GenericDevice d(generic({wide, coil}));
  ScriptedTransport bus;
  Result r = d.writeSignal(bus, 0, 1);
  EXPECT_EQ(r.error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(r.message,
            "wide: write_function 6 (write single register) cannot write the 2 registers of "
            "uint32; use 16 (write multiple registers)");
  r = d.writeSignal(bus, 1, 1);
  EXPECT_EQ(r.error, ErrorKind::kInvalidArgument);
  EXPECT_NE(r.message.find("coil: write_function 16 is not a coil write"), std::string::npos)
      << r.message;
  EXPECT_EQ(bus.executed(), 0);
}

TEST(GenericDevice, HasNoOutputs) {
  GenericDevice d(generic({sig("a", kH, 0)}));
  EXPECT_EQ(d.checkOutputs({0}, {true}), "channels: a generic device has no outputs");
  ScriptedTransport bus;
  EXPECT_EQ(OutputBatch::write(d, bus, {0}, {true}).error, ErrorKind::kInvalidArgument);
  EXPECT_EQ(bus.executed(), 0);
}

TEST(GenericDevice, TheRegistryBuildsIt) {
  EXPECT_EQ(validateDeviceConfig(generic({sig("a", kH, 0)})), "");
  auto d = createDevice(generic({sig("a", kH, 0)}));
  ASSERT_TRUE(d);
  EXPECT_STREQ(d->type(), "generic");
  DeviceConfig bad = generic({sig("a", kH, 0)});
  bad.address = 248;
  EXPECT_EQ(validateDeviceConfig(bad), "devices/meter/address: 248 is outside 1-247 for generic");
}

// Issue 24: min/max bound the value the device gets. Scale 10, max 95: 95 rounds to raw 10,
// which is 100 on the device, and must be refused; 90 (raw 9) and 100 with max 100 pass.
TEST(GenericDevice, MinMaxAreCheckedOnTheRoundedValue) {
  auto sp = sig("flow", kH, 10, SignalType::kUint16);
  sp.writable = true;
  sp.scale = 10;
  sp.max = 95;
  sp.min = 12;
  sp.unit = "l/h";
  auto tenth = sig("temp", kH, 11, SignalType::kInt16);
  tenth.writable = true;
  tenth.scale = 0.1;
  tenth.max = 0.3;  // 3 * 0.1 is 0.30000000000000004: not "above" 0.3
  GenericDevice d(generic({sp, tenth}));
  ScriptedTransport bus;  // nothing may be sent for the refused ones
  EXPECT_EQ(d.writeSignal(bus, 0, 95).message,
            "flow: 95 l/h would be written as 100 l/h (raw 10), outside 12 to 95 l/h");
  EXPECT_EQ(d.writeSignal(bus, 0, 14).message,
            "flow: 14 l/h would be written as 10 l/h (raw 1), outside 12 to 95 l/h");
  // A `.nan` comes back as "nan", never "-nan" (issue #33 item 5).
  EXPECT_EQ(d.writeSignal(bus, 0, -std::nan("")).message.find("-nan"), std::string::npos);
  EXPECT_NE(d.writeSignal(bus, 0, -std::nan("")).message.find("nan"), std::string::npos);
  EXPECT_EQ(bus.executed(), 0);
  std::vector<uint16_t> words;
  EXPECT_EQ(d.encodeWrite(0, 90, &words), "");
  EXPECT_EQ(words, std::vector<uint16_t>{9});
  EXPECT_EQ(d.encodeWrite(0, 16, &words), "");  // raw 2 = 20: inside
  EXPECT_EQ(d.encodeWrite(1, 0.3, &words), "");
  EXPECT_EQ(words, std::vector<uint16_t>{3});
}

// Issue 24: a NaN reading is the same reading as the NaN before it (published once).
TEST(GenericDevice, ANanReadingIsTheSameReadingAsTheLastNan) {
  EXPECT_TRUE(sameReading(std::nan(""), std::nan("")));
  EXPECT_TRUE(sameReading(1.5, 1.5));
  EXPECT_FALSE(sameReading(std::nan(""), 1.5));
  EXPECT_FALSE(sameReading(1.5, std::nan("")));
  // As the device decodes it: float32 0x7FC00000 twice.
  GenericDevice d(generic({sig("power", kI, 0, SignalType::kFloat32)}));
  ScriptedTransport bus;
  expectRead(bus, Request::readInputRegisters(5, 0, 2), {0x7FC0, 0});
  ASSERT_TRUE(d.poll(bus).ok());
  const double first = d.states()[0].value;
  expectRead(bus, Request::readInputRegisters(5, 0, 2), {0x7FC0, 0});
  ASSERT_TRUE(d.poll(bus).ok());
  EXPECT_TRUE(std::isnan(first));
  EXPECT_TRUE(sameReading(first, d.states()[0].value));
  EXPECT_SCRIPT_DONE(bus);
}

// Issue 24: a merged read refused with exception 03 (Eastron meters refuse over-long reads so)
// is split as after 02, and the split remembered.
TEST(GenericDevice, AMergedReadRefusedWithException03IsSplit) {
  GenericDevice d(
      generic({sig("a", kI, 0, SignalType::kFloat32), sig("b", kI, 6, SignalType::kFloat32)}));
  ScriptedTransport bus;
  expectRefused(bus, Request::readInputRegisters(5, 0, 8), kIllegalDataValue);
  expectRead(bus, Request::readInputRegisters(5, 0, 2), {0x4366, 0});
  expectRead(bus, Request::readInputRegisters(5, 6, 2), {0x3FC0, 0});
  const Result r = d.poll(bus);
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(d.states()[0].value, 230.0);
  EXPECT_EQ(d.states()[1].value, 1.5);
  ASSERT_EQ(d.splits().size(), 1u);
  EXPECT_NE(d.splits()[0].find("refused (exception 03)"), std::string::npos) << d.splits()[0];
  expectRead(bus, Request::readInputRegisters(5, 0, 2), {0x4366, 0});
  expectRead(bus, Request::readInputRegisters(5, 6, 2), {0x3FC0, 0});
  EXPECT_TRUE(d.poll(bus).ok());
  EXPECT_SCRIPT_DONE(bus);
}

// Issue 24/6: the fail-safe writes each safe_value and reads it back; a refusal does not stop
// the others, a silent device does.
TEST(GenericDevice, SafeValuesAreWrittenAndReadBack) {
  auto speed = sig("speed", kH, 10, SignalType::kInt16);
  speed.writable = true;
  speed.scale = 0.1;
  speed.safe_value = -2.5;
  auto run = sig("run", Table::kCoil, 3);
  run.writable = true;
  run.safe_value = 0;
  auto free = sig("free", kH, 11);
  free.writable = true;
  GenericDevice d(generic({speed, free, run}));
  EXPECT_EQ(d.safeSignals(), (std::vector<size_t>{0, 2}));
  ScriptedTransport bus;
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleRegister(5, 10, 0xFFE7))));  // -25
  expectRead(bus, Request::readHoldingRegisters(5, 10, 1), {0xFFE7});
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleCoil(5, 3, false))));
  expectRead(bus, Request::readCoils(5, 3, 1), {0});
  const Result r = d.writeSafeValues(bus, d.safeSignals());
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(d.states()[0].value, -2.5, 1e-9);
  EXPECT_EQ(d.states()[2].value, 0.0);
  EXPECT_SCRIPT_DONE(bus);

  // The register refuses the write (exception 04): the coil is still written; the failure
  // names the signal. The read-back showing another value is a failure too.
  expectRefused(bus, Request::writeSingleRegister(5, 10, 0xFFE7), kSlaveDeviceFailure);
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleCoil(5, 3, false))));
  expectRead(bus, Request::readCoils(5, 3, 1), {1});
  const Result refused = d.writeSafeValues(bus, d.safeSignals());
  EXPECT_FALSE(refused.ok());
  EXPECT_EQ(refused.message.rfind("speed: ", 0), 0u) << refused.message;
  EXPECT_SCRIPT_DONE(bus);

  // Issue #32 item 10: a value the device does not keep (read back 0, not -2.5) is its answer:
  // the coil is still written, and the device is not taken as silent (nothing to retry).
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleRegister(5, 10, 0xFFE7))));
  expectRead(bus, Request::readHoldingRegisters(5, 10, 1), {0});
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleCoil(5, 3, false))));
  expectRead(bus, Request::readCoils(5, 3, 1), {0});
  std::vector<size_t> not_reached{99};
  const Result not_kept = d.writeSafeValues(bus, d.safeSignals(), &not_reached);
  EXPECT_FALSE(not_kept.ok());
  EXPECT_TRUE(not_reached.empty());
  EXPECT_NE(not_kept.message.find("speed is 0"), std::string::npos) << not_kept.message;
  EXPECT_SCRIPT_DONE(bus);

  // Silence (the write, and the read-back that tells whether it was done): the coil is not
  // tried.
  bus.expect(toHex(encodeRequest(Request::writeSingleRegister(5, 10, 0xFFE7))));
  bus.expect(toHex(encodeRequest(Request::readHoldingRegisters(5, 10, 1))));
  EXPECT_EQ(d.writeSafeValues(bus, d.safeSignals(), &not_reached).error, ErrorKind::kTimeout);
  EXPECT_EQ(not_reached, (std::vector<size_t>{0, 2}));
  EXPECT_SCRIPT_DONE(bus);

  // Only the signals asked for: the coil alone.
  bus.expectEcho(toHex(encodeRequest(Request::writeSingleCoil(5, 3, false))));
  expectRead(bus, Request::readCoils(5, 3, 1), {0});
  EXPECT_TRUE(d.writeSafeValues(bus, {2}).ok());
  EXPECT_SCRIPT_DONE(bus);
}
