#include "modbus_rtu_driver/tools/commission_values.h"

#include <cctype>
#include <sstream>

namespace modbus_rtu_driver::commission_args {

[[noreturn]] void bad(const std::string& message) {
  throw BadArgument{message};
}

// Decimal, or hexadecimal with 0x; the whole text must be the number.
bool toLong(const std::string& text, long* out) {
  const bool hex = text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X');
  const std::string digits = hex ? text.substr(2) : text;
  if (digits.empty() || digits.size() > 9) return false;
  for (size_t i = 0; i < digits.size(); ++i) {
    const auto c = static_cast<unsigned char>(digits[i]);
    const bool sign = i == 0 && c == '-' && !hex && digits.size() > 1;
    if (!(hex ? std::isxdigit(c) : std::isdigit(c)) && !sign) return false;
  }
  *out = std::stol(digits, nullptr, hex ? 16 : 10);
  return true;
}

// "'text' is outside lo-hi", or "" when text is an integer in lo-hi.
std::string outsideInts(const std::string& text, long lo, long hi) {
  long v = 0;
  if (toLong(text, &v) && v >= lo && v <= hi) return "";
  return "'" + text + "' is outside " + std::to_string(lo) + "-" + std::to_string(hi);
}

int intIn(const std::string& what, const std::string& text, int lo, int hi) {
  const std::string problem = outsideInts(text, lo, hi);
  if (!problem.empty()) bad(what + ": " + problem);
  long v = 0;
  toLong(text, &v);
  return static_cast<int>(v);
}

// The same check on a value CLI11 already converted.
void checkIn(const std::string& what, int value, int lo, int hi) {
  if (value < lo || value > hi)
    bad(what + ": '" + std::to_string(value) + "' is outside " + std::to_string(lo) + "-" +
        std::to_string(hi));
}

bool toDouble(const std::string& text, double* out) {
  std::istringstream in(text);
  char rest = 0;
  return (in >> *out) && !(in >> rest);
}

std::string rangeText(double lo, double hi) {
  std::ostringstream range;
  range << lo << "-" << hi;
  return range.str();
}

// "a, b,c" -> {"a", "b", "c"}
std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  std::istringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    const size_t first = item.find_first_not_of(' '), last = item.find_last_not_of(' ');
    items.push_back(first == std::string::npos ? "" : item.substr(first, last - first + 1));
  }
  return items;
}

// "a, b or c"
std::string orList(const std::vector<std::string>& items) {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i)
    out += (i == 0 ? "" : i + 1 == items.size() ? " or " : ", ") + items[i];
  return out;
}

}  // namespace modbus_rtu_driver::commission_args
