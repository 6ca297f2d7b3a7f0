// CLI11's checks of one option's value on its own, for the commissioning tool's command line:
// the check is CLI11's (CLI::Range, CLI::IsMember), the refusal is in this tool's words, and
// CLI11 puts the option's name in front.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace modbus_rtu_driver::commission_args {

using Message = std::function<std::string(const std::string&)>;
CLI::Validator refusing(const CLI::Validator& check, const Message& message);
// An integer in lo-hi, decimal or 0x-hex, rewritten as decimal for CLI11 to convert (so "010"
// is ten with every CLI11 version, not octal).
CLI::Validator intRange(long lo, long hi);
// An integer whose range depends on another value (COUNT: on the table), checked after parsing.
CLI::Validator anInteger(const std::string& range);
CLI::Validator secondsRange(double lo, double hi);
// A standard rate (core/config/link_config.h), checked as an integer first.
CLI::Validator baudRate();
// A parity by its name (parseParity's check: a letter is refused with the name to write).
CLI::Validator parityWords(const std::string& suffix = "");
// The name, checked, as its Parity's number for CLI11 to convert.
CLI::Validator parityOption();

// --bauds and --parities of scan: lists, or all. Functions, not global validators: the CLI11
// 2.4 test builds these files into its program beside the library built with the system's
// CLI11, and an exported global would be built and destroyed by both.
CLI::Validator baudList();
CLI::Validator parityList();
// A table by its one name; a spelling of earlier versions is refused with the name to use.
CLI::Validator tableName();

}  // namespace modbus_rtu_driver::commission_args
