// Human and JSON output of modbus_rtu_commission.
#include "modbus_rtu_driver/tools/commission_output.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ostream>

#include "modbus_rtu_driver/tools/commission.h"

namespace modbus_rtu_driver {

Json& Json::add(const std::string& key, int value) {
  value_[key] = value;
  return *this;
}

Json& Json::add(const std::string& key, double value) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", std::isfinite(value) ? value : 0.0);
  const double rounded = std::strtod(buf, nullptr);
  if (std::fabs(rounded) < 1e15 && rounded == std::floor(rounded))
    value_[key] = static_cast<int64_t>(rounded);
  else
    value_[key] = rounded;
  return *this;
}

Json& Json::add(const std::string& key, bool value) {
  value_[key] = value;
  return *this;
}

Json& Json::add(const std::string& key, const std::string& value) {
  value_[key] = value;
  return *this;
}

Json& Json::add(const std::string& key, const std::vector<uint16_t>& values) {
  value_[key] = values;
  return *this;
}

Json& Json::add(const std::string& key, const std::vector<Json>& objects) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const Json& object : objects) list.push_back(object.value_);
  value_[key] = std::move(list);
  return *this;
}

Json& Json::merge(const Json& other) {
  for (const auto& field : other.value_.items()) value_[field.key()] = field.value();
  return *this;
}

int exitCodeFor(const Result& r) {
  switch (r.error) {
    case ErrorKind::kNone:
      return kExitOk;
    case ErrorKind::kTimeout:
      return kExitNotFound;
    case ErrorKind::kException:
      // A gateway's 0B / 0A are no device's refusal: nobody answered, or its line is not open.
      if (r.exception_code == kGatewayTargetFailed) return kExitNotFound;
      if (r.exception_code == kGatewayPathUnavailable) return kExitBusError;
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
