// A health level that only escalates until it is reset: within a reporting period the worst
// thing that happened is what gets reported (in /diagnostics and in service answers).
#pragma once

#include <cstdint>
#include <string>

namespace modbus_rtu_driver {

enum class Level : uint8_t { kOk = 0, kWarn = 1, kError = 2, kStale = 3 };
const char* levelName(Level level);

class Status {
 public:
  // Raises the level (never lowers it); the message of the highest level is kept.
  void escalate(Level level, const std::string& message);
  void reset(Level level = Level::kOk, const std::string& message = "OK");
  Level level() const { return level_; }
  const std::string& message() const { return message_; }

 private:
  Level level_ = Level::kOk;
  std::string message_ = "OK";
};

}  // namespace modbus_rtu_driver
