#include "modbus_rtu_driver/sim/sim_device_commands.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <iterator>
#include <vector>

#include "modbus_rtu_driver/core/modbus/switch_words.h"

namespace modbus_rtu_driver {

const char* const kSimGetSetUsage =
    "usage: get|set DEVICE coil|discrete_input|holding_register|input_register ADDRESS [COUNT | "
    "VALUES...]";

bool parseControlNumber(const std::string& text, long min, long max, long* out) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 0);
  if (errno || *end || v < min || v > max) return false;
  *out = v;
  return true;
}

bool isSimDeviceCommand(const std::string& verb) {
  static const char* kDeviceVerbs[] = {"get",     "set",      "silence",       "fail",
                                       "corrupt", "truncate", "wrong_address", "noise",
                                       "late",    "drop",     "stats"};
  return std::find(std::begin(kDeviceVerbs), std::end(kDeviceVerbs), verb) !=
         std::end(kDeviceVerbs);
}

std::string simDeviceCommand(const std::string& verb, SimDevice& d, std::istream& in,
                             SimClock::time_point now, bool* stored) {
  *stored = false;
  std::string a, b;
  long n = 0, address = 0;
  if (verb == "stats")
    return "ok changes " + std::to_string(d.changes) + " dropped_requests " +
           std::to_string(d.dropped_requests) + " dropped_replies " +
           std::to_string(d.dropped_replies);
  if (verb == "silence" || verb == "fail") {
    in >> a;
    if (a.empty()) a = "1";
    const auto on = parseSwitch(a);
    if (!on) return "error " + verb + ": '" + a + "' is not one of " + std::string(kSwitchWords);
    (verb == "silence" ? d.silenced : d.failing) = *on;
    return "ok";
  }
  if (verb == "drop") {
    in >> a >> b;
    if (!parseControlNumber(a, 0, 100, &n))
      return "error drop: '" + a + "' is not a percentage 0-100";
    if (b != "request" && b != "reply") return "error drop: say request or reply, not '" + b + "'";
    (b == "request" ? d.drop_request_percent : d.drop_reply_percent) = static_cast<int>(n);
    return "ok";
  }
  if (verb == "corrupt" || verb == "truncate" || verb == "wrong_address" || verb == "noise" ||
      verb == "late") {
    in >> a;
    if (!parseControlNumber(a, 0, 1000000, &n))
      return "error " + verb + ": '" + a + "' is not a count";
    if (verb == "late") {
      in >> b;
      if (!parseControlNumber(b, 0, 60000, &address))
        return "error late: '" + b + "' is not 0-60000 milliseconds";
      d.late_ms = static_cast<int>(address);
    }
    int& counter = verb == "corrupt"    ? d.corrupt_replies
                   : verb == "truncate" ? d.truncate_replies
                   : verb == "noise"    ? d.noise_replies
                   : verb == "late"     ? d.late_replies
                                        : d.wrong_address_replies;
    counter = static_cast<int>(n);
    return "ok";
  }
  if (!(in >> a)) return std::string("error no table; ") + kSimGetSetUsage;
  std::string table_error;
  const auto parsed_table = parseTableName(a, &table_error);
  if (!parsed_table) return "error table " + table_error + "; " + kSimGetSetUsage;
  const Table table = *parsed_table;
  if (!(in >> b) || !parseControlNumber(b, 0, 0xFFFF, &address))
    return "error address '" + b + "' is not 0-65535; " + std::string(kSimGetSetUsage);
  if (verb == "get") {
    long count = 1;
    if (in >> b && !parseControlNumber(b, 1, 2000, &count))
      return "error count '" + b + "' is not 1-2000";
    std::string out = "ok";
    for (long i = address; i < address + count; ++i) {
      uint16_t v = 0;
      const uint8_t e = i > 0xFFFF ? static_cast<uint8_t>(kIllegalDataAddress)
                                   : d.read(table, static_cast<uint16_t>(i), now, &v);
      if (e) return "error " + exceptionName(e) + " at " + std::to_string(i);
      out += " " + std::to_string(v);
    }
    return out;
  }
  std::vector<uint16_t> values;
  while (in >> b) {
    long v = 0;
    if (!parseControlNumber(b, -32768, 65535, &v)) return "error value '" + b + "' is not 16 bits";
    values.push_back(static_cast<uint16_t>(v));  // negative: two's complement (temperature)
  }
  if (values.empty()) return "error set needs at least one value; " + std::string(kSimGetSetUsage);
  if (address + static_cast<long>(values.size()) > 0x10000)
    return "error " + exceptionName(kIllegalDataAddress) + " at 65536";
  if (table == Table::kCoil || table == Table::kHoldingRegister) {  // one write, checked as a whole
    for (uint16_t v : values)
      if (table == Table::kCoil && v > 1) return "error coil values are 0 or 1";
    const uint8_t e = d.write(table, static_cast<uint16_t>(address), values, now);
    if (e) return "error " + exceptionName(e) + " at " + std::to_string(address);
    *stored = true;
    return "ok";
  }
  for (size_t i = 0; i < values.size(); ++i) {
    const long at = address + static_cast<long>(i);
    const uint8_t e = d.setDirect(table, static_cast<uint16_t>(at), values[i], now);
    if (e) return "error " + exceptionName(e) + " at " + std::to_string(at);
  }
  *stored = true;
  return "ok";
}

}  // namespace modbus_rtu_driver
