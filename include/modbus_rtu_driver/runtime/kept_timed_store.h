// Where a bus keeps its running timed commands for the next node (docs/failsafe.md, "What the
// node cannot do"): the parameter server in the node (ros/running_timed_parameter.h), a map that
// outlives the simulated node in the fail-safe's simulation. ROS-free.
#pragma once

#include <string>
#include <vector>

#include "modbus_rtu_driver/failsafe/kept_timed_commands.h"

namespace modbus_rtu_driver {

class KeptTimedStore {
 public:
  virtual ~KeptTimedStore() = default;
  // What the previous node kept for `device`.
  virtual std::vector<KeptTimedCommand> read(const std::string& device) const = 0;
  // Any thread, without waiting: `device`'s running timed commands are now `kept` (none: none
  // are kept for it).
  virtual void keep(const std::string& device, std::vector<KeptTimedCommand> kept) = 0;
  // Now, in the seconds the kept ends are counted in: wall-clock time in the node (the list
  // outlives the process), the simulation's clock there.
  virtual double seconds() const = 0;
};

}  // namespace modbus_rtu_driver
