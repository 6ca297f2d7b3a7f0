#include "modbus_rtu_driver/core/status.h"

namespace modbus_rtu_driver {

const char* levelName(Level level) {
  switch (level) {
    case Level::kOk:
      return "OK";
    case Level::kWarn:
      return "WARN";
    case Level::kError:
      return "ERROR";
    case Level::kStale:
      return "STALE";
  }
  return "?";
}

void Status::escalate(Level level, const std::string& message) {
  if (level < level_) return;
  if (level == level_ && level_ != Level::kOk) return;  // keep the first message of a level
  level_ = level;
  message_ = message;
}

void Status::reset(Level level, const std::string& message) {
  level_ = level;
  message_ = message;
}

}  // namespace modbus_rtu_driver
