// Human and JSON output of modbus_rtu_commission.
#include "modbus_rtu_driver/tools/commission_output.h"

#include <cmath>
#include <cstdio>
#include <ostream>

#include "modbus_rtu_driver/tools/commission.h"

namespace modbus_rtu_driver {

std::string Json::quote(const std::string& text) {
  std::string s = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      s += '\\';
      s += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      s += buf;
    } else {
      s += c;
    }
  }
  return s + "\"";
}

Json& Json::addRaw(const std::string& key, const std::string& json) {
  body_ += (body_.empty() ? "" : ",") + quote(key) + ":" + json;
  return *this;
}

Json& Json::merge(const Json& other) {
  if (!other.body_.empty()) body_ += (body_.empty() ? "" : ",") + other.body_;
  return *this;
}

Json& Json::add(const std::string& key, int value) {
  return addRaw(key, std::to_string(value));
}

Json& Json::add(const std::string& key, double value) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", std::isfinite(value) ? value : 0.0);
  return addRaw(key, buf);
}

Json& Json::add(const std::string& key, bool value) {
  return addRaw(key, value ? "true" : "false");
}

Json& Json::add(const std::string& key, const std::string& value) {
  return addRaw(key, quote(value));
}

Json& Json::add(const std::string& key, const std::vector<uint16_t>& values) {
  std::string list = "[";
  for (size_t i = 0; i < values.size(); ++i) list += (i ? "," : "") + std::to_string(values[i]);
  return addRaw(key, list + "]");
}

int exitCodeFor(const Result& r) {
  switch (r.error) {
    case ErrorKind::kNone:
      return kExitOk;
    case ErrorKind::kTimeout:
      return kExitNotFound;
    case ErrorKind::kException:
      return kExitRefused;
    case ErrorKind::kInvalidArgument:
      return kExitBadArguments;
    default:  // CRC, wrong address, malformed, I/O, port closed
      return kExitBusError;
  }
}

void Output::result(const std::string& human, const Json& fields) {
  if (json_)
    out_ << Json().add("ok", true).merge(fields).str() << "\n" << std::flush;
  else
    out_ << human << "\n" << std::flush;
}

void Output::event(const std::string& human, const Json& fields) {
  out_ << (json_ ? fields.str() : human) << "\n" << std::flush;
}

int Output::fail(int exit_code, const std::string& message) {
  if (json_)
    out_ << Json().add("ok", false).add("exit", exit_code).add("error", message).str() << "\n"
         << std::flush;
  else
    err_ << "error: " << message << "\n" << std::flush;
  return exit_code;
}

int Output::fail(const Result& r, const std::string& context) {
  std::string message = context.empty() ? r.message : context + ": " + r.message;
  if (r.error == ErrorKind::kCrc)
    message += " (line noise, a wrong baud or parity, or two devices answering at once)";
  return fail(exitCodeFor(r), message);
}

void Output::note(const std::string& text) {
  err_ << text << "\n" << std::flush;
}

}  // namespace modbus_rtu_driver
