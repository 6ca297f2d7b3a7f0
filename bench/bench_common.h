// What the parts of modbus_rtu_benchmark share (defined in benchmark.cpp): the rate loop and the
// plain libmodbus reference call every table compares against.
#pragma once

#include <modbus/modbus.h>
#include <sched.h>

#include <fstream>
#include <functional>
#include <string>

#include "modbus_rtu_driver/core/types.h"

namespace modbus_rtu_driver {

// Transactions per second of `once` over `seconds` (0 when one of them failed).
double transactionRate(double seconds, const std::function<bool()>& once);
// `r` through libmodbus's own API on `ctx`: true when it succeeded.
bool plainLibmodbus(modbus_t* ctx, const Request& r);

// While it lives, this thread and the threads it starts (a simulator, a server, a pymodbus
// client) run on one CPU: a client and its server on one CPU or on two move single rounds by up
// to 1.5 x, and the comparison is between software, not thread placements.
class PinnedToOneCpu {
 public:
  PinnedToOneCpu() {
    if (sched_getaffinity(0, sizeof saved_, &saved_) != 0) return;
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
      if (!CPU_ISSET(cpu, &saved_)) continue;
      cpu_set_t one;
      CPU_ZERO(&one);
      CPU_SET(cpu, &one);
      pinned_ = sched_setaffinity(0, sizeof one, &one) == 0;
      return;
    }
  }
  ~PinnedToOneCpu() {
    if (pinned_) sched_setaffinity(0, sizeof saved_, &saved_);
  }
  PinnedToOneCpu(const PinnedToOneCpu&) = delete;
  PinnedToOneCpu& operator=(const PinnedToOneCpu&) = delete;

 private:
  cpu_set_t saved_{};
  bool pinned_ = false;
};

void benchmarkScale(const std::string& dir, double seconds, std::ofstream& csv);
void benchmarkTransports(const std::string& dir, double seconds, std::ofstream& csv);

}  // namespace modbus_rtu_driver
