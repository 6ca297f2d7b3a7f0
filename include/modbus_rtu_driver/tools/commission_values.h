// The commissioning tool's command line: numbers and lists read from its words, and the
// refusal that names the option and its range (commission_args.cpp).
#pragma once

#include <string>
#include <vector>

namespace modbus_rtu_driver::commission_args {

// A refused command line: parseCommission gives `message` to the caller.
struct BadArgument {
  std::string message;
};
[[noreturn]] void bad(const std::string& message);

// Decimal, or hexadecimal with 0x; the whole text must be the number.
bool toLong(const std::string& text, long* out);
// "'text' is outside lo-hi", or "" when text is an integer in lo-hi.
std::string outsideInts(const std::string& text, long lo, long hi);
int intIn(const std::string& what, const std::string& text, int lo, int hi);
// The same check on a value CLI11 already converted.
void checkIn(const std::string& what, int value, int lo, int hi);
bool toDouble(const std::string& text, double* out);
std::string rangeText(double lo, double hi);
// "a, b,c" -> {"a", "b", "c"}
std::vector<std::string> splitList(const std::string& text);
// "a, b or c"
std::string orList(const std::vector<std::string>& items);

}  // namespace modbus_rtu_driver::commission_args
