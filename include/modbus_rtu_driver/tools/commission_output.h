// What modbus_rtu_commission prints: human-readable text by default, one JSON object per line
// with --json (for scripts). Errors carry the exit code that tells their kind apart.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/modbus/types.h"

namespace modbus_rtu_driver {

// A JSON object built field by field, in insertion order (nlohmann::ordered_json).
class Json {
 public:
  Json& add(const std::string& key, int value);
  // Rounded to 6 significant digits (what the registers can hold and more); integers print
  // without a fraction, non-finite values as 0.
  Json& add(const std::string& key, double value);
  Json& add(const std::string& key, bool value);
  Json& add(const std::string& key, const std::string& value);
  Json& add(const std::string& key, const char* value) { return add(key, std::string(value)); }
  Json& add(const std::string& key, const std::vector<uint16_t>& values);
  Json& add(const std::string& key, const std::vector<Json>& objects);  // an array of objects
  Json& merge(const Json& other);                                       // other's fields after ours
  // Compact, one line; bytes that are not UTF-8 (a device's or the user's text) become U+FFFD.
  std::string str() const {
    return value_.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
  }

 private:
  nlohmann::ordered_json value_ = nlohmann::ordered_json::object();
};

// Exit code for the outcome of a transaction.
int exitCodeFor(const Result& result);

class Output {
 public:
  Output(bool json, std::ostream& out, std::ostream& err) : json_(json), out_(out), err_(err) {}
  bool json() const { return json_; }

  // The command's outcome: `human` on stdout, or {"ok":true, fields...}.
  void result(const std::string& human, const Json& fields);
  // One event of a long command (a device found, a change seen): `human` or `fields` as is.
  void event(const std::string& human, const Json& fields);
  // Refusals and failures: "error: ..." on stderr, or {"ok":false,"exit":N,"error":...}.
  int fail(int exit_code, const std::string& message);
  int fail(const Result& result, const std::string& context = "");
  // Reminders and warnings, on stderr in both modes.
  void note(const std::string& text);
  std::ostream& err() { return err_; }

 private:
  bool json_;
  std::ostream& out_;
  std::ostream& err_;
};

}  // namespace modbus_rtu_driver
