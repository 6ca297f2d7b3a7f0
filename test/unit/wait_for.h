// Waiting for a condition with a bounded deadline: tests that read a counter, a state or a
// reply after an event wait for it rather than reading once (a loaded machine is slow, not
// wrong).
#pragma once

#include <chrono>
#include <functional>
#include <thread>

namespace modbus_rtu_driver {

// True as soon as `condition` holds; false if it still does not after `seconds`.
inline bool waitFor(const std::function<bool()>& condition, double seconds = 10.0) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

}  // namespace modbus_rtu_driver
