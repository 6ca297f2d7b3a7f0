#include "modbus_rtu_driver/core/bus/rate_meter.h"

namespace modbus_rtu_driver {

void RateMeter::record(time_point when) {
  std::lock_guard<std::mutex> lock(mutex_);
  times_.push_back(when);
  while (times_.size() > 2 && when - times_.front() > std::chrono::seconds(5)) times_.pop_front();
}

double RateMeter::rate() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (times_.size() < 2) return 0.0;
  const double span = std::chrono::duration<double>(times_.back() - times_.front()).count();
  return span > 0 ? static_cast<double>(times_.size() - 1) / span : 0.0;
}

}  // namespace modbus_rtu_driver
