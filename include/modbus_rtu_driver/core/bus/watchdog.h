// A heartbeat watchdog on an injected clock (any thread): armed from construction, it expires
// `timeout` after the last feed (or the start) and says so once; a feed re-arms it.
#pragma once

#include <chrono>
#include <mutex>

#include "modbus_rtu_driver/core/bus/clock.h"

namespace modbus_rtu_driver {

class Watchdog {
 public:
  Watchdog(double timeout_s, Clock& clock = Clock::steady())
      : timeout_(
            std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s))),
        clock_(clock),
        last_feed_(clock.now()) {}

  void feed() {
    std::lock_guard<std::mutex> lock(mutex_);
    last_feed_ = clock_.now();
    tripped_ = false;
  }
  // True once when the timeout has passed since the last feed; false again until fed.
  bool expired() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (tripped_ || clock_.now() - last_feed_ < timeout_) return false;
    tripped_ = true;
    return true;
  }
  bool tripped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return tripped_;
  }

 private:
  mutable std::mutex mutex_;
  Clock::duration timeout_;
  Clock& clock_;
  Clock::time_point last_feed_;
  bool tripped_ = false;
};

}  // namespace modbus_rtu_driver
