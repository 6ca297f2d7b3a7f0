// modbus_rtu_commission's settings commands and type identification, frame by frame: the
// manuals' frames where they print them, a harmless read of the current value before each
// change, nothing written without confirmation, and an exit code per kind of failure.
#include "test_commission_script.h"

using namespace modbus_rtu_driver;

namespace {
using R = Request;
}

TEST_F(CommissionOnScript, Ld58a08AddressThrough0xFFWithTheManualsFrames) {
  bus_.expect("FF 03 00 FD 00 01 00 24", golden("FF 03 00 FD 00 01 00 24"));  // answers 1
  EXPECT_EQ(run({"get-address", "--type", "ld58a08"}), kExitOk);
  EXPECT_EQ(out_.str(), "ld58a08 address: 1\n");
  EXPECT_NE(err_.str().find("right only with one ld58a08 on the bus"), std::string::npos);

  bus_.expect("FF 03 00 FD 00 01 00 24", golden("FF 03 00 FD 00 01 00 24"))
      .expect("FF 06 00 FD 00 02 8C 25", golden("FF 06 00 FD 00 02 8C 25"))
      .expect(frame(R::readHoldingRegisters(2, 0x00FD, 1)),
              reply(R::readHoldingRegisters(2, 0x00FD, 1), {2}));
  EXPECT_EQ(run({"--yes", "set-address", "--type", "ld58a08", "2"}), kExitOk);
  EXPECT_EQ(out_.str(), "ld58a08 address changed from 1 to 2; it answers at 2\n");
}

TEST_F(CommissionOnScript, Ld58a08AddressAtItsAddressIsCheckedAtTheNewOne) {
  const R current = R::readHoldingRegisters(1, 0x00FD, 1);
  const R at_new = R::readHoldingRegisters(2, 0x00FD, 1);
  bus_.expect(frame(current), reply(current, {1}))
      .expect("01 06 00 FD 00 02 99 FB", golden("01 06 00 FD 00 02 99 FB"))
      .expect(frame(at_new));  // silent at the new address
  EXPECT_EQ(run({"--yes", "--json", "set-address", "--type", "ld58a08", "--address", "1", "2"}),
            kExitOk);
  EXPECT_EQ(out_.str(),
            "{\"ok\":true,\"type\":\"ld58a08\",\"previous\":1,\"address\":2,\"answers\":false}\n");
  EXPECT_NE(err_.str().find("does not answer there yet"), std::string::npos);
}

TEST_F(CommissionOnScript, Ld58a08FactoryResetThrough0xFFIsTheManualsFrame) {
  bus_.expect("FF 06 00 FB 00 00 ED E5", golden("FF 06 00 FB 00 00 ED E5"));
  EXPECT_EQ(run({"--yes", "factory-reset", "--type", "ld58a08"}), kExitOk);
  EXPECT_NE(out_.str().find("factory settings restored"), std::string::npos);
  EXPECT_NE(out_.str().find("powered off and on"), std::string::npos);
}

TEST_F(CommissionOnScript, LcBoardAddressThroughZeroWithTheManualsFrames) {
  bus_.expect("00 03 00 00 00 01 85 DB", golden("00 03 00 00 00 01 85 DB"));  // answers 255
  EXPECT_EQ(run({"get-address", "--type", "lc_relay8"}), kExitOk);
  EXPECT_EQ(out_.str(), "lc_relay8 address: 255\n");

  R at_zero = R::readHoldingRegisters(0, 0, 1);
  at_zero.single_device_at_zero = true;
  bus_.expect("00 03 00 00 00 01 85 DB", reply(at_zero, {7}))
      .expect("00 10 00 00 00 01 02 00 FF EB 80", golden("00 10 00 00 00 01 02 00 FF EB 80"))
      .expect("FF 03 03 E8 00 01 11 A4", golden("FF 03 03 E8 00 01 11 A4"));  // it answers at 255
  EXPECT_EQ(run({"--yes", "set-address", "--type", "lc_relay8", "255"}), kExitOk);
  EXPECT_EQ(out_.str(), "lc_relay8 address changed from 7 to 255; it answers at 255\n");
}

// The LC board has no address register at its own address: get-address there asks whether it
// answers (its baud code read, as the manual prints it).
TEST_F(CommissionOnScript, LcBoardAtAnAddressOnlyAnswersOrNot) {
  bus_.expect("FF 03 03 E8 00 01 11 A4", golden("FF 03 03 E8 00 01 11 A4"));
  EXPECT_EQ(run({"get-address", "--type", "lc_relay8", "--address", "255"}), kExitOk);
  EXPECT_EQ(out_.str(), "lc_relay8 answers at address 255\n");
  bus_.expect("FF 03 03 E8 00 01 11 A4");  // silence
  EXPECT_EQ(run({"get-address", "--type", "lc_relay8", "--address", "255"}), kExitNotFound);
  EXPECT_NE(err_.str().find("asking the lc_relay8 at address 255"), std::string::npos)
      << err_.str();
}

TEST_F(CommissionOnScript, LcBoardAddressChangeStopsWhenAnotherBoardAnswers) {
  R at_zero = R::readHoldingRegisters(0, 0, 1);
  at_zero.single_device_at_zero = true;
  bus_.expect("00 03 00 00 00 01 85 DB", reply(at_zero, {7}));
  EXPECT_EQ(run({"--yes", "set-address", "--type", "lc_relay8", "--address", "9", "20"}),
            kExitNotFound);
  EXPECT_NE(err_.str().find("reports address 7, not 9; nothing was changed"), std::string::npos);
}

TEST_F(CommissionOnScript, BaudChangesWithTheManualsFramesAndThePowerCycleReminder) {
  bus_.expect("FF 03 03 E8 00 01 11 A4", golden("FF 03 03 E8 00 01 11 A4"))  // now code 4
      .expect("FF 10 03 E9 00 01 02 00 03 8B CC", golden("FF 10 03 E9 00 01 02 00 03 8B CC"));
  EXPECT_EQ(run({"--yes", "set-baud", "--type", "lc_relay8", "--address", "255", "9600"}), kExitOk);
  EXPECT_EQ(out_.str(),
            "lc_relay8 at address 255: baud rate set to 9600 baud (code 3) (was 19200 baud (code "
            "4)). It takes effect after the device is powered off and on (the manual advises "
            "about 30 s without power); then reach it with --baud 9600.\n");

  bus_.expect("01 03 00 FE 00 01 E5 FA", golden("01 03 00 FE 00 01 E5 FA"))  // now code 3
      .expect("01 06 00 FE 00 02 69 FB", golden("01 06 00 FE 00 02 69 FB"));
  EXPECT_EQ(run({"--yes", "set-baud", "--type", "ld58a08", "--address", "1", "2"}), kExitOk);
  EXPECT_NE(out_.str().find("set to 4800 baud (code 2) (was 9600 baud (code 3)). It takes effect "
                            "after the device is powered off and on"),
            std::string::npos)
      << out_.str();
}

TEST_F(CommissionOnScript, ParityAndReturnDelayWithTheManualsFrames) {
  const R parity = R::readHoldingRegisters(1, 0x00FF, 1);
  bus_.expect(frame(parity), reply(parity, {0}))
      .expect("01 06 00 FF 00 01 78 3A", golden("01 06 00 FF 00 01 78 3A"));
  EXPECT_EQ(run({"--yes", "set-parity", "--address", "1", "even"}), kExitOk);
  EXPECT_NE(out_.str().find("powered off and on; then reach it with --parity even"),
            std::string::npos);

  const R delay = R::readHoldingRegisters(1, 0x00FC, 1);
  bus_.expect(frame(delay), reply(delay, {0}))
      .expect("01 06 00 FC 00 05 89 F9", golden("01 06 00 FC 00 05 89 F9"));
  EXPECT_EQ(run({"--yes", "--json", "set-return-delay", "--address", "1", "200"}), kExitOk);
  EXPECT_EQ(out_.str().find("{\"ok\":true,\"type\":\"ld58a08\",\"address\":1,\"return_delay_ms\":"
                            "200,\"previous\":0,\"changed\":true,\"note\":"),
            0u)
      << out_.str();
}

TEST_F(CommissionOnScript, NothingIsWrittenWithoutConfirmation) {
  const R baud = R::readHoldingRegisters(1, 0x00FE, 1);
  bus_.expect(frame(baud), reply(baud, {3}));
  EXPECT_EQ(run({"set-baud", "--type", "ld58a08", "--address", "1", "19200"}, "n\n"),
            kExitNotConfirmed);
  EXPECT_NE(err_.str().find("Change the baud rate of the ld58a08 at address 1 from 9600 baud "
                            "(code 3) to 19200 baud (code 4)? It takes effect after the device "
                            "is powered off and on"),
            std::string::npos)
      << err_.str();
  bus_.expect(frame(baud), reply(baud, {3}));
  EXPECT_EQ(run({"set-baud", "--type", "ld58a08", "--address", "1", "19200"}, ""),  // EOF
            kExitNotConfirmed);
  bus_.expect(frame(baud), reply(baud, {3}))
      .expectEcho(frame(R::writeSingleRegister(1, 0x00FE, 4)));
  EXPECT_EQ(run({"set-baud", "--type", "ld58a08", "--address", "1", "19200"}, "y\n"), kExitOk);
  EXPECT_EQ(bus_.executed(), 4);
}

TEST_F(CommissionOnScript, ASettingAlreadyInPlaceIsNotWritten) {
  const R parity = R::readHoldingRegisters(1, 0x00FF, 1);
  bus_.expect(frame(parity), reply(parity, {0}));
  EXPECT_EQ(run({"set-parity", "--address", "1", "none"}), kExitOk);
  EXPECT_EQ(out_.str(), "ld58a08 at address 1: parity is already none; nothing written\n");
}

TEST_F(CommissionOnScript, PowerDownSaveNeedsNoConfirmation) {
  const R save = R::readHoldingRegisters(1, 0x00FA, 1);
  bus_.expect(frame(save), reply(save, {0})).expectEcho(frame(R::writeSingleRegister(1, 0xFA, 1)));
  EXPECT_EQ(run({"set-save", "--address", "1", "on"}, ""), kExitOk);  // no question asked
  EXPECT_EQ(err_.str(), "");
}

TEST_F(CommissionOnScript, ExitCodesTellNoAnswerRefusalAndBusErrorsApart) {
  const R baud = R::readHoldingRegisters(1, 0x00FE, 1);
  bus_.expect(frame(baud));  // silence
  EXPECT_EQ(run({"get-baud", "--type", "ld58a08", "--address", "1"}), kExitNotFound);
  bus_.expect(frame(baud), exception(baud, kIllegalDataAddress));
  EXPECT_EQ(run({"get-baud", "--type", "ld58a08", "--address", "1"}), kExitRefused);
  EXPECT_NE(err_.str().find("illegal data address"), std::string::npos) << err_.str();
  bus_.expect(frame(baud), "01 03 02 00 03 F8 46");  // the manual's reply with a broken CRC
  EXPECT_EQ(run({"--json", "get-baud", "--type", "ld58a08", "--address", "1"}), kExitBusError);
  EXPECT_EQ(out_.str().find("{\"ok\":false,\"exit\":5,\"error\":"), 0u) << out_.str();

  const R address = R::readHoldingRegisters(1, 0x00FD, 1);
  const R write = R::writeSingleRegister(1, 0x00FD, 9);
  bus_.expect(frame(address), reply(address, {1}))
      .expect(frame(write), exception(write, kIllegalDataValue));
  EXPECT_EQ(run({"--yes", "set-address", "--type", "ld58a08", "--address", "1", "9"}),
            kExitRefused);
  EXPECT_NE(err_.str().find("writing the ld58a08 address"), std::string::npos) << err_.str();
}

TEST_F(CommissionOnScript, InfoReadsTheSettingsOfTheTypeFound) {
  const R coils = R::readCoils(1, 0, 1);
  const R address = R::readHoldingRegisters(1, 0x00FD, 1);
  const R settings = R::readHoldingRegisters(1, 0x00FA, 6);
  bus_.expect(frame(coils), reply(coils, {0}))
      .expect(frame(address), reply(address, {1}))
      .expect(frame(settings), reply(settings, {1, 0, 5, 1, 4, 2}));
  EXPECT_EQ(run({"info", "--address", "1"}), kExitOk);
  EXPECT_EQ(out_.str(),
            "address 1: ld58a08\n  stored baud rate: 19200 baud (code 4)\n  stored parity: odd\n"
            "  return delay: 200 ms\n  power-down save: on\n");
}

// Identification: reads only, and an answer of any kind (even an exception) counts as present.
TEST_F(CommissionOnScript, IdentificationByHarmlessReads) {
  auto coils = [](uint8_t a) { return R::readCoils(a, 0, 1); };
  auto own = [](uint8_t a) { return R::readHoldingRegisters(a, 0x00FD, 1); };
  auto pdu = [](uint8_t a) { return R::readInputRegisters(a, 0, 5); };
  auto lc = [](uint8_t a) { return R::readHoldingRegisters(a, 0x03E8, 1); };

  bus_.expect(frame(coils(1)), reply(coils(1), {0})).expect(frame(own(1)), reply(own(1), {1}));
  EXPECT_EQ(identifyDevice(bus_, 1).type, "ld58a08");

  bus_.expect(frame(coils(2)), reply(coils(2), {0}))
      .expect(frame(own(2)), exception(own(2), kIllegalDataAddress))
      .expect(frame(pdu(2)), reply(pdu(2), {220, 550, 2201, 25, 52}));
  EXPECT_EQ(identifyDevice(bus_, 2).type, "yespeed_pdu");

  bus_.expect(frame(coils(255)), reply(coils(255), {1}))
      .expect(frame(own(255)), exception(own(255), kIllegalDataAddress))
      .expect(frame(pdu(255)), exception(pdu(255), kIllegalFunction))
      .expect(frame(lc(255)), reply(lc(255), {3}));
  EXPECT_EQ(identifyDevice(bus_, 255).type, "lc_relay8");

  bus_.expect(frame(coils(5)), exception(coils(5), kIllegalFunction))
      .expect(frame(own(5)), exception(own(5), kIllegalFunction))
      .expect(frame(pdu(5)), exception(pdu(5), kIllegalFunction))
      .expect(frame(lc(5)), exception(lc(5), kIllegalFunction));
  const Identity unknown = identifyDevice(bus_, 5);
  EXPECT_TRUE(unknown.present);
  EXPECT_EQ(unknown.type, "unknown modbus device");

  bus_.expect(frame(coils(9)));  // silence: one read, nothing more
  EXPECT_FALSE(identifyDevice(bus_, 9).present);
  std::string garbled = reply(coils(9), {0});
  garbled.back() = garbled.back() == '0' ? '1' : '0';  // bad CRC
  bus_.expect(frame(coils(9)), garbled);               // noise at a wrong baud: not a device
  EXPECT_FALSE(identifyDevice(bus_, 9).present);

  // An LD58A08 at 1 answering 0xFF is not a device at 255.
  bus_.expect(frame(coils(255)), reply(coils(255), {0}))
      .expect(frame(own(255)), reply(own(255), {1}))
      .expect(frame(pdu(255)), exception(pdu(255), kIllegalFunction))
      .expect(frame(lc(255)), exception(lc(255), kIllegalDataAddress));
  const Identity ghost = identifyDevice(bus_, 255);
  EXPECT_FALSE(ghost.present);
  EXPECT_EQ(ghost.note, "address 255: an LD58A08 answered for its address 1");
}

// Issue #13/9: the PDU's limits with the manual's frames (7.4 read, 7.5 FC16 write).
TEST_F(CommissionOnScript, PduLimitsWithTheManualsFrames) {
  bus_.expect("01 03 00 00 00 03 05 CB", golden("01 03 00 00 00 03 05 CB"));  // 250, 200, 16
  EXPECT_EQ(run({"get-limits", "--address", "1"}), kExitOk);
  EXPECT_EQ(out_.str(),
            "yespeed_pdu at address 1, limits: over-voltage 250.0 V, under-voltage 200.0 V, "
            "over-current 16.00 A\n");
  bus_.expect("01 03 00 00 00 03 05 CB", golden("01 03 00 00 00 03 05 CB"));
  EXPECT_EQ(run({"--json", "get-limits", "--address", "1"}), kExitOk);
  EXPECT_EQ(out_.str(),
            "{\"ok\":true,\"type\":\"yespeed_pdu\",\"address\":1,\"over_voltage\":250,"
            "\"under_voltage\":200,\"over_current\":16,\"registers\":[2500,2000,1600]}\n");

  const R write = R::writeMultipleRegisters(1, 0, {2600, 1600, 700});
  const R back = R::readHoldingRegisters(1, 0, 3);
  bus_.expect("01 03 00 00 00 03 05 CB", golden("01 03 00 00 00 03 05 CB"))
      .expect("01 10 00 00 00 03 06 0A 28 06 40 02 BC 87 A1", reply(write))
      .expect("01 03 00 00 00 03 05 CB", reply(back, {2600, 1600, 700}));
  EXPECT_EQ(run({"--yes", "set-limits", "--address", "1", "--over-voltage", "260",
                 "--under-voltage", "160", "--over-current", "7"}),
            kExitOk);
  EXPECT_EQ(out_.str(),
            "yespeed_pdu at address 1: limits set to over-voltage 260.0 V, under-voltage 160.0 V, "
            "over-current 7.00 A (was over-voltage 250.0 V, under-voltage 200.0 V, over-current "
            "16.00 A); read back\n");
}

TEST_F(CommissionOnScript, PduSetLimitsKeepsTheOthersAsksAndChecksTheMergedValues) {
  const std::string read = "01 03 00 00 00 03 05 CB", holds = golden(read);  // 250, 200, 16
  // One limit: the others as the PDU holds them; nothing without a "y".
  bus_.expect(read, holds);
  EXPECT_EQ(run({"set-limits", "--address", "1", "--over-voltage", "260"}, "n\n"),
            kExitNotConfirmed);
  EXPECT_NE(err_.str().find("Change the limits of the yespeed_pdu at address 1 from over-voltage "
                            "250.0 V, under-voltage 200.0 V, over-current 16.00 A to "
                            "over-voltage 260.0 V, under-voltage 200.0 V, over-current 16.00 A?"),
            std::string::npos)
      << err_.str();
  const R write = R::writeMultipleRegisters(1, 0, {2600, 2000, 1600});
  const R back = R::readHoldingRegisters(1, 0, 3);
  bus_.expect(read, holds)
      .expect(frame(write), reply(write))
      .expect(read, reply(back, {2600, 2000, 1600}));
  EXPECT_EQ(run({"set-limits", "--address", "1", "--over-voltage", "260"}, "y\n"), kExitOk);

  // 190 V alone is fine, but not above the PDU's own under-voltage 200 V: nothing written.
  bus_.expect(read, holds);
  EXPECT_EQ(run({"--yes", "set-limits", "--address", "1", "--over-voltage", "190"}),
            kExitBadArguments);
  EXPECT_NE(err_.str().find("over_voltage: 190.0 V must be above under_voltage (200.0 V)"),
            std::string::npos)
      << err_.str();

  // Refused by the PDU (exception 03), or not what it holds afterwards: never a success.
  const R other = R::writeMultipleRegisters(1, 0, {2500, 2000, 700});
  bus_.expect(read, holds).expect(frame(other), exception(other, kIllegalDataValue));
  EXPECT_EQ(run({"--yes", "set-limits", "--address", "1", "--over-current", "7"}), kExitRefused);
  bus_.expect(read, holds).expect(frame(other), reply(other)).expect(read, holds);  // still 16 A
  EXPECT_NE(run({"--yes", "set-limits", "--address", "1", "--over-current", "7"}), kExitOk);
  EXPECT_NE(err_.str().find("holds 250.0 V / 200.0 V / 16.00 A"), std::string::npos) << err_.str();

  // Already so: nothing written.
  bus_.expect(read, holds);
  EXPECT_EQ(run({"set-limits", "--address", "1", "--over-current", "16"}), kExitOk);
  EXPECT_EQ(out_.str(),
            "yespeed_pdu at address 1: limits are already over-voltage 250.0 V, under-voltage "
            "200.0 V, over-current 16.00 A; nothing written\n");
}

// Issue #13/9: an LC board at 255 answers the LD58A08's address read with exception 02.
TEST_F(CommissionOnScript, Ld58a08AddressReadRefusedHintsAtAnotherBoardType) {
  const R own = R::readHoldingRegisters(0xFF, 0x00FD, 1);
  bus_.expect("FF 03 00 FD 00 01 00 24", exception(own, kIllegalDataAddress));
  EXPECT_EQ(run({"get-address", "--type", "ld58a08"}), kExitRefused);
  EXPECT_NE(err_.str().find("illegal data address"), std::string::npos) << err_.str();
  EXPECT_NE(err_.str().find("another board type may have answered (e.g. an LC relay board at "
                            "its factory address 255: try --type lc_relay8)"),
            std::string::npos)
      << err_.str();
  const R at7 = R::readHoldingRegisters(7, 0x00FD, 1);
  bus_.expect(frame(at7), exception(at7, kIllegalDataAddress));
  EXPECT_EQ(run({"get-address", "--type", "ld58a08", "--address", "7"}), kExitRefused);
  EXPECT_NE(err_.str().find("another board type may be at 7 (info --address 7 names it)"),
            std::string::npos)
      << err_.str();
}

// A type the tool has never heard of: registering its class (as a new type's own
// src/devices/<type>_commissioning.cpp does) is all it takes for the tool to offer its
// settings, check its ranges and name its factory settings.
namespace {

inline constexpr DeviceDescriptor kRelayTestType{
    "relay_test", 100, 4, 0, {7, 19200, Parity::kEven}, "test/unit/test_commission_device.cpp"};

class RelayTestCommissioning : public Commissioning {
 public:
  static constexpr uint16_t kBaudRegister = 0x0010, kResetRegister = 0x0011;
  int probeOrder() const override { return 5; }
  // Sends nothing: the other tests' scripts stay as they are.
  Probe probe(Transport&, uint8_t) const override { return {}; }
  Result report(Transport&, uint8_t, InfoReport*) const override { return Result::success(); }
  bool has(BoardFeature f) const override {
    return f == BoardFeature::kBaud || f == BoardFeature::kFactoryReset;
  }
  std::string title() const override { return "the test relay"; }
  std::pair<int, int> baudCodes() const override { return {3, 5}; }  // 9600, 19200, 38400
  Result readSetting(Transport& transport, int address, BoardFeature, uint16_t* v) const override {
    Result r = transport.execute(
        Request::readHoldingRegisters(static_cast<uint8_t>(address), kBaudRegister, 1));
    if (r.ok()) *v = r.values[0];
    return r;
  }
  Result writeSetting(Transport& transport, int address, BoardFeature, uint16_t v) const override {
    return transport.execute(
        Request::writeSingleRegister(static_cast<uint8_t>(address), kBaudRegister, v));
  }
  Result factoryReset(Transport& transport, int address) const override {
    return transport.execute(
        Request::writeSingleRegister(static_cast<uint8_t>(address), kResetRegister, 1));
  }
};

const RelayTestCommissioning kRelayTest;
[[maybe_unused]] const bool kRelayTestRegistered =
    commissioningClasses().add(kRelayTestType, &kRelayTest);

}  // namespace

TEST_F(CommissionOnScript, ANewTypesSettingsNeedNoEditOfTheTool) {
  const R baud = R::readHoldingRegisters(3, 0x0010, 1);
  bus_.expect(frame(baud), reply(baud, {3}))
      .expectEcho(frame(R::writeSingleRegister(3, 0x0010, 5)));
  EXPECT_EQ(run({"--yes", "set-baud", "--type", "relay_test", "--address", "3", "38400"}), kExitOk);
  EXPECT_EQ(out_.str(),
            "relay_test at address 3: baud rate set to 38400 baud (code 5) (was 9600 baud (code "
            "3)). It takes effect after the device is powered off and on; then reach it with "
            "--baud 38400.\n");

  // Its factory settings come from its descriptor; it has no address every board takes, so
  // --address is needed.
  bus_.expectEcho(frame(R::writeSingleRegister(3, 0x0011, 1)));
  EXPECT_EQ(run({"factory-reset", "--type", "relay_test", "--address", "3"}, "y\n"), kExitOk);
  EXPECT_NE(err_.str().find("Reset the relay_test at address 3 to factory settings: address 7, "
                            "19200 baud, even parity?"),
            std::string::npos)
      << err_.str();
  EXPECT_NE(out_.str().find("factory settings restored (address 7, 19200 8E1)"), std::string::npos)
      << out_.str();

  // Its ranges and the commands it has not, before anything is sent.
  CommissionCommand c;
  std::string error;
  EXPECT_FALSE(parseCommission({"--port", "/dev/null", "factory-reset", "--type", "relay_test"}, &c,
                               &error));
  EXPECT_EQ(error, "--address: missing (1-100)");
  EXPECT_FALSE(parseCommission(
      {"--port", "/dev/null", "get-baud", "--type", "relay_test", "--address", "101"}, &c, &error));
  EXPECT_EQ(error, "--address: '101' is outside 1-100");
  EXPECT_FALSE(parseCommission(
      {"--port", "/dev/null", "set-baud", "--type", "relay_test", "--address", "3", "4800"}, &c,
      &error));
  EXPECT_EQ(error, "baud: '4800' is neither a code 3-5 nor one of 9600, 19200, 38400 (relay_test)");
  EXPECT_FALSE(parseCommission(
      {"--port", "/dev/null", "get-address", "--type", "relay_test", "--address", "3"}, &c,
      &error));
  EXPECT_EQ(error,
            "--type: get-address is an ld58a08 or lc_relay8 command; the test relay has no such "
            "setting");
  EXPECT_FALSE(parseCommission(
      {"--port", "/dev/null", "get-address", "--type", "relay", "--address", "3"}, &c, &error));
  EXPECT_EQ(error, "--type: 'relay' is not ld58a08 or lc_relay8");
  EXPECT_FALSE(parseCommission(
      {"--port", "/dev/null", "get-parity", "--type", "relay_test", "--address", "3"}, &c, &error));
  EXPECT_EQ(error, "--type: get-parity is an ld58a08 command; the test relay has no such setting");
  // --help names it, its factory settings and its manual.
  EXPECT_TRUE(parseCommission({"--help"}, &c, &error));
  EXPECT_NE(c.help.find("relay_test: addresses 1-100, factory address 7, 19200 8E1 "
                        "(test/unit/test_commission_device.cpp)"),
            std::string::npos)
      << c.help;
}

// The registered types probe in the order their classes give: the LD58A08 first (it answers
// 0xFF for its own address), the LC board's loose check last.
TEST(CommissionTypes, ProbeOrderAndFactorySettingsComeFromTheRegistry) {
  std::vector<std::string> names;
  for (const CommissioningType& t : commissioningTypes()) names.emplace_back(t.type->name);
  EXPECT_EQ(names, (std::vector<std::string>{"relay_test", "ld58a08", "yespeed_pdu", "lc_relay8"}));
  CommissionCommand c;
  std::string error;
  ASSERT_TRUE(parseCommission({"--help"}, &c, &error));
  for (const char* line : {"ld58a08: addresses 1-248, factory address 1, 9600 8N1, return delay "
                           "up to 1000 ms (docs/devices/ld58a08.md)",
                           "lc_relay8: addresses 1-255, factory address 255, 9600 8N1 "
                           "(docs/devices/lc_relay8.md)",
                           "ld58a08 boards also answer some requests at 255:\n      move "
                           "lc_relay8 boards off their factory address 255"})
    EXPECT_NE(c.help.find(line), std::string::npos) << line << "\n" << c.help;
}
