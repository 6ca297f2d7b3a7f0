// The parameter server's running_timed/<device> lists for the fail-safe's simulation: a map the
// harness owns, so that it outlives a killed or stopped node as roscore does, with the ends in
// the simulation's clock's seconds. ROS-free.
#pragma once

#include <chrono>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/runtime/kept_timed_store.h"

namespace modbus_rtu_driver {

class MemoryKeptTimed : public KeptTimedStore {
 public:
  explicit MemoryKeptTimed(Clock& clock) : clock_(clock) {}
  std::vector<KeptTimedCommand> read(const std::string& device) const override {
    const auto it = lists_.find(device);
    return it == lists_.end() ? std::vector<KeptTimedCommand>{} : it->second;
  }
  // Without a list, the key goes (as RunningTimedParameter deletes it).
  void keep(const std::string& device, std::vector<KeptTimedCommand> kept) override {
    if (kept.empty())
      lists_.erase(device);
    else
      lists_[device] = std::move(kept);
  }
  double seconds() const override {
    return std::chrono::duration<double>(clock_.now().time_since_epoch()).count();
  }

 private:
  Clock& clock_;
  std::map<std::string, std::vector<KeptTimedCommand>> lists_;
};

}  // namespace modbus_rtu_driver
