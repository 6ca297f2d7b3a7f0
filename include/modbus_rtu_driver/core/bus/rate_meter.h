// How often something happened lately: the rate of the events of the last 5 s. The bus
// scheduler measures each device's polls with it, a generic device each of its poll groups.
// Events are recorded on the bus thread and the rate is read by diagnostics: both lock.
#pragma once

#include <chrono>
#include <deque>
#include <mutex>

namespace modbus_rtu_driver {

class RateMeter {
 public:
  using time_point = std::chrono::steady_clock::time_point;
  void record(time_point when);
  // Hz over the events still in the window; 0 before the second event.
  double rate() const;

 private:
  mutable std::mutex mutex_;
  std::deque<time_point> times_;
};

}  // namespace modbus_rtu_driver
