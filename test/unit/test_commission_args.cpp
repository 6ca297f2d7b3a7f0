// modbus_rtu_commission's command line: what each command parses to, and every bad value
// refused with a message naming the option and its range (before any port is opened).
#include <gtest/gtest.h>

#include "modbus_rtu_driver/tools/commission.h"

using namespace modbus_rtu_driver;

namespace {

// Parses `--port /dev/null` + args; fails the test when parsing fails.
CommissionCommand parsed(std::vector<std::string> args) {
  args.insert(args.begin(), {"--port", "/dev/null"});
  CommissionCommand c;
  std::string error;
  EXPECT_TRUE(parseCommission(args, &c, &error)) << error;
  return c;
}

// The error message for `--port /dev/null` + args; empty when it parses.
std::string refusal(std::vector<std::string> args, bool with_port = true) {
  if (with_port) args.insert(args.begin(), {"--port", "/dev/null"});
  CommissionCommand c;
  std::string error;
  return parseCommission(args, &c, &error) ? "" : error;
}

// The whole --help text, as `modbus_rtu_commission --help` prints it.
std::string commissionUsage() {
  CommissionCommand c;
  std::string error;
  EXPECT_TRUE(parseCommission({"--help"}, &c, &error)) << error;
  return c.help;
}

}  // namespace

TEST(CommissionArgs, ScanDefaultsCoverEveryAddressAtTheGivenLine) {
  const CommissionCommand c = parsed({"scan"});
  EXPECT_EQ(c.link.port, "/dev/null");
  ASSERT_EQ(c.addresses.size(), 255u);  // 255 included: the LC board's factory address
  EXPECT_EQ(c.addresses.front(), 1);
  EXPECT_EQ(c.addresses.back(), 255);
  EXPECT_EQ(c.bauds, std::vector<int>{9600});
  ASSERT_EQ(c.parities.size(), 1u);
  EXPECT_EQ(c.parities[0], Parity::kNone);
  EXPECT_EQ(c.link.retries, 0);
  // Short per-address wait for scans: 50 ms plus 30 characters at 9600 8N1.
  EXPECT_NEAR(c.link.response_timeout, 0.05 + 30 * 10.0 / 9600, 1e-9);
  EXPECT_FALSE(c.first_only);
}

TEST(CommissionArgs, ScanLists) {
  CommissionCommand c = parsed({"scan", "--addresses", "1-3,255,2", "--bauds", "all", "--parities",
                                "all", "--first", "--timeout", "0.3"});
  EXPECT_EQ(c.addresses, (std::vector<int>{1, 2, 3, 255}));
  EXPECT_EQ(c.bauds, (std::vector<int>{1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200}));
  EXPECT_EQ(c.parities, (std::vector<Parity>{Parity::kNone, Parity::kEven, Parity::kOdd}));
  EXPECT_TRUE(c.first_only);
  EXPECT_DOUBLE_EQ(c.link.response_timeout, 0.3);
  c = parsed(
      {"--baud", "19200", "--parity", "even", "scan", "--from", "250", "--bauds", "9600, 19200"});
  EXPECT_EQ(c.addresses.size(), 6u);
  EXPECT_EQ(c.bauds, (std::vector<int>{9600, 19200}));
  EXPECT_EQ(c.parities, std::vector<Parity>{Parity::kEven});  // --parity is the default
}

// Through a Modbus TCP gateway (the node's share) a scan waits for the gateway's own answer
// (0B comes after its timeout); a transparent rtu+tcp:// gateway answers nothing itself.
TEST(CommissionArgs, ScansThroughAModbusTcpGatewayWaitForItsAnswer) {
  auto timeout = [](const std::vector<std::string>& args) {
    CommissionCommand c;
    std::string error;
    EXPECT_TRUE(parseCommission(args, &c, &error)) << error;
    return c.link.response_timeout;
  };
  EXPECT_DOUBLE_EQ(timeout({"--port", "tcp://127.0.0.1:1502", "scan"}), kGatewayScanTimeout);
  EXPECT_DOUBLE_EQ(timeout({"--port", "tcp://127.0.0.1:1502", "--timeout", "0.5", "scan"}), 0.5);
  EXPECT_NEAR(timeout({"--port", "rtu+tcp://127.0.0.1:1502", "scan"}), 0.05 + 30 * 10.0 / 9600,
              1e-9);
}

TEST(CommissionArgs, OtherCommandsWaitOutTheLongestReturnDelay) {
  EXPECT_GT(parsed({"read", "--address", "1", "coil", "0"}).link.response_timeout, 1.0);
  EXPECT_DOUBLE_EQ(
      parsed({"--timeout", "2", "read", "--address", "1", "coil", "0"}).link.response_timeout, 2.0);
}

TEST(CommissionArgs, SettingsAreParsedIntoTheBoardsOwnCodes) {
  EXPECT_EQ(parsed({"set-baud", "--type", "ld58a08", "--address", "1", "19200"}).new_value, 4);
  EXPECT_EQ(parsed({"set-baud", "--type", "ld58a08", "--address", "1", "4"}).new_value, 4);
  EXPECT_EQ(parsed({"set-baud", "--type", "ld58a08", "--address", "1", "1200"}).new_value, 0);
  EXPECT_EQ(parsed({"set-baud", "--type", "ld58a08", "--address", "1", "115200"}).new_value, 7);
  EXPECT_EQ(parsed({"set-baud", "--type", "lc_relay8", "--address", "255", "4800"}).new_value, 2);
  EXPECT_EQ(parsed({"set-baud", "--type", "lc_relay8", "--address", "255", "3"}).new_value, 3);
  EXPECT_EQ(parsed({"set-parity", "--address", "1", "none"}).new_value, 0);
  EXPECT_EQ(parsed({"set-parity", "--address", "1", "even"}).new_value, 1);
  EXPECT_EQ(parsed({"set-parity", "--address", "1", "odd"}).new_value, 2);
  EXPECT_EQ(parsed({"set-return-delay", "--address", "1", "200"}).new_value, 5);
  EXPECT_EQ(parsed({"set-return-delay", "--address", "1", "1000"}).new_value, 25);
  EXPECT_EQ(parsed({"set-save", "--address", "1", "on"}).new_value, 1);
  EXPECT_EQ(parsed({"set-save", "--address", "1", "off"}).new_value, 0);
  // The one set of on/off words the node's configuration and the simulator take too.
  EXPECT_EQ(parsed({"set-save", "--address", "1", "yes"}).new_value, 1);
  EXPECT_EQ(parsed({"set-save", "--address", "1", "FALSE"}).new_value, 0);
  EXPECT_EQ(parsed({"set-save", "--address", "1", "1"}).new_value, 1);
  const CommissionCommand reset = parsed({"factory-reset"});
  EXPECT_EQ(reset.type, "ld58a08");  // the LD-only commands need no --type
  EXPECT_EQ(reset.address, -1);      // through 0xFF
  const CommissionCommand lc = parsed({"--yes", "set-address", "--type", "lc_relay8", "255"});
  EXPECT_EQ(lc.new_value, 255);
  EXPECT_TRUE(lc.yes);
}

TEST(CommissionArgs, TablesAcceptDecimalAndHex) {
  CommissionCommand c =
      parsed({"--json", "read", "--address", "0x01", "holding_register", "0xFD", "3"});
  EXPECT_TRUE(c.json);
  EXPECT_EQ(c.address, 1);
  EXPECT_EQ(c.table, Table::kHoldingRegister);
  EXPECT_EQ(c.start, 253);
  EXPECT_EQ(c.count, 3);
  EXPECT_EQ(parsed({"read", "--address", "010", "coil", "0"}).address, 10);  // not octal
  c = parsed({"write", "--address", "255", "coil", "0", "1", "0", "1", "--multiple"});
  EXPECT_EQ(c.values, (std::vector<uint16_t>{1, 0, 1}));
  EXPECT_EQ(c.count, 3);
  EXPECT_TRUE(c.multiple);
  c = parsed(
      {"watch", "--address", "2", "input_register", "0", "5", "--interval", "0.2", "--count", "7"});
  EXPECT_EQ(c.count, 5);
  EXPECT_DOUBLE_EQ(c.interval, 0.2);
  EXPECT_EQ(c.polls, 7);
}

TEST(CommissionArgs, AddressesOutsideTheBoardsRangeAreRefused) {
  EXPECT_EQ(refusal({"set-address", "--type", "ld58a08", "0"}),
            "new address: '0' is outside 1-248");
  // The LD58A08 manual allows 1-248 (0x01-0xF8).
  EXPECT_EQ(refusal({"set-address", "--type", "ld58a08", "249"}),
            "new address: '249' is outside 1-248");
  EXPECT_EQ(parsed({"set-address", "--type", "ld58a08", "248"}).new_value, 248);
  EXPECT_EQ(parsed({"get-baud", "--type", "ld58a08", "--address", "248"}).address, 248);
  EXPECT_EQ(refusal({"set-address", "--type", "lc_relay8", "256"}),
            "new address: '256' is outside 1-255");
  EXPECT_EQ(refusal({"set-address", "--type", "lc_relay8", "0"}),
            "new address: '0' is outside 1-255");
  EXPECT_EQ(refusal({"get-baud", "--type", "ld58a08", "--address", "249"}),
            "--address: '249' is outside 1-248");
  EXPECT_EQ(refusal({"read", "--address", "0", "coil", "0"}), "--address: '0' is outside 1-255");
  EXPECT_EQ(refusal({"set-address", "--type", "ld58a08"}), "value: missing (see --help)");
  EXPECT_EQ(refusal({"set-address", "5"}), "--type: missing (ld58a08 or lc_relay8)");
  EXPECT_EQ(refusal({"set-address", "--type", "relay", "5"}),
            "--type: 'relay' is not ld58a08 or lc_relay8");
}

TEST(CommissionArgs, SettingsOutsideTheManualsRangesAreRefused) {
  const std::string ld_bauds = "1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200";
  EXPECT_EQ(refusal({"set-baud", "--type", "ld58a08", "--address", "1", "9"}),
            "baud: '9' is neither a code 0-7 nor one of " + ld_bauds + " (ld58a08)");
  // Code 8 resets the board to factory settings: that is factory-reset's job.
  EXPECT_NE(refusal({"set-baud", "--type", "ld58a08", "--address", "1", "8"}), "");
  EXPECT_NE(refusal({"set-baud", "--type", "ld58a08", "--address", "1", "9601"}), "");
  EXPECT_EQ(refusal({"set-baud", "--type", "lc_relay8", "--address", "1", "115200"}),
            "baud: '115200' is neither a code 2-4 nor one of 4800, 9600, 19200 (lc_relay8)");
  EXPECT_NE(refusal({"set-baud", "--type", "lc_relay8", "--address", "1", "5"}), "");
  EXPECT_EQ(refusal({"set-parity", "--address", "1", "mark"}),
            "parity: 'mark' is not one of none, even, odd");
  EXPECT_EQ(refusal({"set-return-delay", "--address", "1", "1001"}),
            "return delay: '1001' is outside 0-1000");
  EXPECT_EQ(refusal({"set-return-delay", "--address", "1", "30"}),
            "return delay: 30 ms is not a multiple of 40 ms (0-1000)");
  EXPECT_EQ(refusal({"set-return-delay", "--address", "1", "-40"}),
            "return delay: '-40' is outside 0-1000");
  EXPECT_EQ(refusal({"set-save", "--address", "1", "maybe"}),
            "power-down save: 'maybe' is not one of on/off, true/false, yes/no, 1/0");
  EXPECT_EQ(refusal({"set-parity", "--type", "lc_relay8", "--address", "1", "even"}),
            "--type: set-parity is an ld58a08 command; the LC relay board has no such setting");
  EXPECT_NE(refusal({"factory-reset", "--type", "lc_relay8"}), "");
}

TEST(CommissionArgs, TableRequestsMustFitOneModbusFrame) {
  EXPECT_EQ(refusal({"read", "--address", "1", "holding_register", "0", "126"}),
            "count: '126' is outside 1-125");
  EXPECT_EQ(refusal({"read", "--address", "1", "coil", "0", "2001"}),
            "count: '2001' is outside 1-2000");
  EXPECT_EQ(refusal({"read", "--address", "1", "holding_register", "65535", "2"}),
            "start: 65535 + 2 passes 65535");
  EXPECT_EQ(refusal({"read", "--address", "1", "bits", "0"}),
            "table: 'bits' is not one of coil, discrete_input, holding_register, input_register");
  EXPECT_EQ(refusal({"read", "--address", "1", "holding", "0"}),
            "table: 'holding' is not one of coil, discrete_input, holding_register, "
            "input_register (the table is now named 'holding_register')");
  EXPECT_EQ(refusal({"write", "--address", "1", "input_register", "0", "5"}),
            "table: input_register cannot be written (coil or holding_register)");
  EXPECT_EQ(refusal({"write", "--address", "1", "coil", "0", "2"}), "value: '2' is outside 0-1");
  EXPECT_EQ(refusal({"write", "--address", "1", "holding_register", "0", "65536"}),
            "value: '65536' is outside 0-65535");
  EXPECT_EQ(refusal({"write", "--address", "1", "holding_register", "0"}),
            "value: missing (0-65535)");
  EXPECT_EQ(refusal({"watch", "--address", "1", "coil", "0", "--interval", "0"}),
            "--interval: '0' is outside 0.01-3600 s");
}

TEST(CommissionArgs, LineAndScanOptionsAreChecked) {
  EXPECT_EQ(refusal({"scan"}, false), "--port: missing (the serial device, e.g. /dev/ttyUSB0)");
  EXPECT_EQ(refusal({"--baud", "9601", "scan"}),
            "--baud: '9601' is not one of 1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200");
  EXPECT_EQ(refusal({"--parity", "mark", "scan"}),
            "--parity: 'mark' is not one of none, even, odd");
  EXPECT_EQ(refusal({"--timeout", "0", "scan"}), "--timeout: '0' is outside 0.005-10 s");
  EXPECT_EQ(refusal({"--timeout", "1s", "scan"}), "--timeout: '1s' is outside 0.005-10 s");
  EXPECT_NE(refusal({"scan", "--bauds", "9600,9601"}).find("--bauds: '9601'"), std::string::npos);
  EXPECT_EQ(refusal({"scan", "--parities", "none,mark"}),
            "--parities: 'mark' is not one of none, even, odd (or all)");
  EXPECT_EQ(refusal({"scan", "--from", "9", "--to", "3"}), "--to: '3' is outside 9-255");
  EXPECT_EQ(refusal({"scan", "--from", "0"}), "--from: '0' is outside 1-255");
  EXPECT_EQ(refusal({"scan", "--addresses", "1-5", "--to", "9"}),
            "--addresses: give it or --from/--to, not both");
  EXPECT_EQ(refusal({"scan", "--addresses", "5-2"}), "--addresses: '2' is outside 5-255");
}

TEST(CommissionArgs, UnknownWordsAreRefused) {
  EXPECT_EQ(refusal({}), "command: missing (see --help)");
  EXPECT_EQ(refusal({"frobnicate"}), "command: 'frobnicate' is not known (see --help)");
  EXPECT_EQ(refusal({"scan", "--colour", "red"}), "--colour: not an option of scan (see --help)");
  EXPECT_EQ(refusal({"read", "--address", "1", "coil", "0", "--first"}),
            "--first: not an option of read (see --help)");
  EXPECT_EQ(refusal({"info", "--address"}), "--address: missing value");
  EXPECT_EQ(refusal({"info", "--address", "1", "extra"}), "unexpected argument 'extra'");
  EXPECT_EQ(refusal({"read", "--address", "1", "coil", "zero"}),
            "start: 'zero' is outside 0-65535");
}

TEST(CommissionArgs, HelpListsEveryCommandAndExitCode) {
  const std::string usage = commissionUsage();
  for (const char* word : {"scan",
                           "info",
                           "get-address",
                           "set-address",
                           "get-baud",
                           "set-baud",
                           "get-parity",
                           "set-parity",
                           "set-return-delay",
                           "set-save",
                           "factory-reset",
                           "read",
                           "write",
                           "watch",
                           "--json",
                           "--yes",
                           "powered off and on",
                           "0 ok",
                           "2 bad arguments",
                           "3 not found",
                           "4 refused by the device",
                           "5 other bus error",
                           "6 not confirmed"})
    EXPECT_NE(usage.find(word), std::string::npos) << word;
}

// Issue #13/9: the PDU's limits, each converted to the register value written and checked
// there, before anything is opened or sent.
TEST(CommissionArgs, PduLimitsAreCheckedOnTheRegisterValues) {
  CommissionCommand c = parsed({"set-limits", "--address", "1", "--over-voltage", "260",
                                "--under-voltage", "160", "--over-current", "7"});
  EXPECT_EQ(c.type, "yespeed_pdu");
  EXPECT_EQ(c.limits, (std::vector<int>{2600, 1600, 700}));
  c = parsed({"set-limits", "--address", "2", "--over-voltage", "250"});
  EXPECT_EQ(c.limits, (std::vector<int>{2500, -1, -1}));  // the others stay
  EXPECT_EQ(parsed({"get-limits", "--address", "2", "--type", "yespeed_pdu"}).address, 2);

  EXPECT_EQ(refusal({"set-limits", "--address", "1", "--over-voltage", "180.00001"}),
            "--over-voltage: 180.0 V (register 1800) must be above 180.0 V (1800)");
  EXPECT_EQ(refusal({"set-limits", "--address", "1", "--over-current", "19.999999"}),
            "--over-current: 20.00 A (register 2000) must be between 5.00 A and 20.00 A "
            "(500-2000, exclusive)");
  EXPECT_EQ(refusal({"set-limits", "--address", "1", "--under-voltage", "280.000001"}),
            "--under-voltage: 280.0 V (register 2800) must be below 280.0 V (2800)");
  EXPECT_EQ(refusal({"set-limits", "--address", "1", "--over-current", "7.005"}),
            "--over-current: 7.005 A is outside 0-655.35 A in steps of 0.01 A");
  EXPECT_EQ(refusal({"set-limits", "--address", "1", "--over-current", "7A"}),
            "--over-current: '7A' is not a number (A)");
  EXPECT_EQ(refusal({"set-limits", "--address", "1", "--over-voltage", "200.00001",
                     "--under-voltage", "200", "--over-current", "7"}),
            "--over-voltage: 200.0 V must be above --under-voltage (200.0 V)");
  EXPECT_NE(refusal({"set-limits", "--address", "1"}).find("give at least one of"),
            std::string::npos);
  EXPECT_EQ(refusal({"set-limits", "--address", "248", "--over-voltage", "250"}),
            "--address: '248' is outside 1-247");
  EXPECT_NE(refusal({"get-limits", "--address", "1", "--type", "lc_relay8"})
                .find("--type: get-limits is a yespeed_pdu command"),
            std::string::npos);
  EXPECT_EQ(refusal({"get-limits", "--address", "1", "--over-voltage", "250"}),
            "--over-voltage: not an option of get-limits (see --help)");
}

// The scan's duration in --help, from the code's own timeouts: one read per silent address,
// the scan timeout plus the gap kept before the next request.
TEST(CommissionArgs, TheFullScanDurationInTheHelpFollowsTheTimeouts) {
  const CommissionCommand c = parsed({"scan", "--bauds", "all", "--parities", "all"});
  double seconds = 0;
  for (const int baud : c.bauds)
    for (const Parity parity : c.parities) {
      LinkConfig line = c.link;
      line.baud = baud;
      line.parity = parity;
      seconds += c.addresses.size() * (c.link.response_timeout + effectiveMinGap(line));
    }
  EXPECT_EQ(c.addresses.size() * c.bauds.size() * c.parities.size(), 6120u);
  EXPECT_NEAR(seconds / 60, 9.1, 0.1);
  EXPECT_NE(commissionUsage().find("about 9 minutes"), std::string::npos);
  EXPECT_NE(commissionUsage().find("6120 x 0.081 s = 8.3 min of timeouts + 0.8 min of gaps"),
            std::string::npos);
}

// Each option is converted by CLI11 after its check: hex and the parity names too, and
// "010" is ten with every CLI11 version (2.1 would read it as octal).
TEST(CommissionArgs, OptionsAreConvertedOnceTheirCheckPassed) {
  CommissionCommand c =
      parsed({"--parity", "even", "--baud", "0x4B00", "scan", "--from", "0x10", "--to", "016"});
  EXPECT_EQ(c.link.parity, Parity::kEven);
  EXPECT_EQ(c.link.baud, 19200);
  EXPECT_EQ(c.addresses, std::vector<int>{16});
  EXPECT_EQ(c.parities, std::vector<Parity>{Parity::kEven});
  EXPECT_EQ(parsed({"--timeout", "0.25", "info", "--address", "0xF8"}).address, 248);
  EXPECT_DOUBLE_EQ(parsed({"--timeout", "0.25", "info", "--address", "7"}).link.response_timeout,
                   0.25);
  EXPECT_EQ(refusal({"info", "--address", "0x100"}), "--address: '0x100' is outside 1-255");
  EXPECT_EQ(refusal({"--parity", "X", "scan"}), "--parity: 'X' is not one of none, even, odd");
  EXPECT_EQ(refusal({"--parity", "E", "scan"}),
            "--parity: 'E' is not one of none, even, odd (write 'even')");
  EXPECT_EQ(refusal({"--parity", "1", "scan"}), "--parity: '1' is not one of none, even, odd");
  EXPECT_EQ(refusal({"scan", "--parities", "even,2"}),
            "--parities: '2' is not one of none, even, odd (or all)");
  EXPECT_EQ(refusal({"read", "--address", "1", "holding_register", "0", "0"}),
            "count: '0' is outside 1-125");
  EXPECT_EQ(refusal({"read", "--address", "1", "coil", "0", "many"}),
            "count: 'many' is not a number (1-2000 values of a bit table, 1-125 registers)");
}
