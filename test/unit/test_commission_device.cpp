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
