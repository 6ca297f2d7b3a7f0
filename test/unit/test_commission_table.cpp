// modbus_rtu_commission's read / write / watch, frame by frame with the manuals' frames.
#include "test_commission_script.h"

using namespace modbus_rtu_driver;

namespace {
using R = Request;
}

TEST_F(CommissionOnScript, ReadEveryTable) {
  bus_.expect("01 03 00 80 00 01 85 E2", golden("01 03 00 80 00 01 85 E2"));
  EXPECT_EQ(run({"read", "--address", "1", "holding_register", "0x80"}), kExitOk);
  EXPECT_EQ(out_.str(), "holding_register 128 (0x0080): 124\n");

  bus_.expect("FF 01 00 00 00 08 28 12", golden("FF 01 00 00 00 08 28 12"));
  EXPECT_EQ(run({"--json", "read", "--address", "255", "coil", "0", "8"}), kExitOk);
  EXPECT_EQ(out_.str(),
            "{\"ok\":true,\"address\":255,\"table\":\"coil\",\"start\":0,"
            "\"values\":[1,0,0,0,0,0,0,0]}\n");

  bus_.expect("FF 02 00 00 00 08 6C 12", golden("FF 02 00 00 00 08 6C 12"));
  EXPECT_EQ(run({"read", "--address", "255", "discrete_input", "0", "8"}), kExitOk);
  EXPECT_EQ(out_.str().substr(0, 39), "discrete_input 0: 1\ndiscrete_input 1: 0");

  const R input = R::readInputRegisters(2, 2, 1);
  bus_.expect(frame(input), reply(input, {2301}));
  EXPECT_EQ(run({"read", "--address", "2", "input_register", "2"}), kExitOk);
  EXPECT_EQ(out_.str(), "input_register 2 (0x0002): 2301\n");
}

TEST_F(CommissionOnScript, WriteUsesSingleOrMultipleFunctions) {
  bus_.expect("01 05 00 00 FF 00 8C 3A", golden("01 05 00 00 FF 00 8C 3A"));
  EXPECT_EQ(run({"write", "--address", "1", "coil", "0", "1"}), kExitOk);
  EXPECT_EQ(out_.str(), "wrote coil 0 with function 5; the device confirmed\n");

  bus_.expect("01 0F 00 00 00 08 01 89 3F 33", golden("01 0F 00 00 00 08 01 89 3F 33"));
  EXPECT_EQ(run({"write", "--address", "1", "coil", "0", "1", "0", "0", "1", "0", "0", "0", "1"}),
            kExitOk);
  EXPECT_EQ(out_.str(), "wrote coil 0-7 with function 15; the device confirmed\n");

  bus_.expect("01 06 00 80 00 09 48 24", golden("01 06 00 80 00 09 48 24"));
  EXPECT_EQ(run({"write", "--address", "1", "holding_register", "128", "9"}), kExitOk);

  const R pwm = R::writeMultipleRegisters(1, 0, {500, 200, 0xFFFF});
  bus_.expect("01 10 00 00 00 03 06 01 F4 00 C8 FF FF D6 CA", reply(pwm));
  EXPECT_EQ(
      run({"--json", "write", "--address", "1", "holding_register", "0", "500", "200", "0xFFFF"}),
      kExitOk);
  EXPECT_EQ(out_.str(),
            "{\"ok\":true,\"address\":1,\"table\":\"holding_register\",\"start\":0,\"count\":3,"
            "\"function\":16}\n");

  // The LC board takes its registers by FC16 only, even one.
  bus_.expect("FF 10 03 E9 00 01 02 00 03 8B CC", golden("FF 10 03 E9 00 01 02 00 03 8B CC"));
  EXPECT_EQ(run({"write", "--address", "255", "holding_register", "0x03E9", "3", "--multiple"}),
            kExitOk);

  const R bad = R::writeSingleCoil(1, 9, true);
  bus_.expect(frame(bad), exception(bad, kIllegalDataAddress));
  EXPECT_EQ(run({"write", "--address", "1", "coil", "9", "1"}), kExitRefused);
}

TEST_F(CommissionOnScript, WatchPrintsOnlyChanges) {
  const R in = R::readDiscreteInputs(255, 0, 2);
  bus_.expect(frame(in), reply(in, {0, 0}))
      .expect(frame(in), reply(in, {0, 0}))
      .expect(frame(in), reply(in, {0, 1}))
      .expect(frame(in))  // no answer: said once on stderr, not printed as a change
      .expect(frame(in), reply(in, {0, 1}));
  EXPECT_EQ(run({"watch", "--address", "255", "discrete_input", "0", "2", "--interval", "0.01",
                 "--count", "5"}),
            kExitOk);
  std::istringstream lines(out_.str());
  std::string first, second, third;
  std::getline(lines, first);
  std::getline(lines, second);
  EXPECT_FALSE(std::getline(lines, third)) << out_.str();
  EXPECT_NE(first.find("discrete_input 0: 0, discrete_input 1: 0"), std::string::npos) << first;
  EXPECT_NE(second.find("  discrete_input 1: 0 -> 1"), std::string::npos) << second;
  EXPECT_EQ(second.find("discrete_input 0"), std::string::npos) << second;
  EXPECT_NE(err_.str().find("read failed"), std::string::npos);
  EXPECT_NE(err_.str().find("answering again"), std::string::npos);

  const R coil = R::readCoils(1, 3, 1);
  bus_.expect(frame(coil), reply(coil, {1})).expect(frame(coil), reply(coil, {0}));
  EXPECT_EQ(
      run({"--json", "watch", "--address", "1", "coil", "3", "--interval", "0.01", "--count", "2"}),
      kExitOk);
  EXPECT_NE(out_.str().find("\"values\":[1],\"changed\":[3]}\n{"), std::string::npos);
  EXPECT_NE(out_.str().find("\"values\":[0],\"changed\":[3]}\n"), std::string::npos);

  bus_.expect(frame(coil)).expect(frame(coil));
  EXPECT_EQ(run({"watch", "--address", "1", "coil", "3", "--interval", "0.01", "--count", "2"}),
            kExitNotFound);
  EXPECT_EQ(out_.str(), "");
}
