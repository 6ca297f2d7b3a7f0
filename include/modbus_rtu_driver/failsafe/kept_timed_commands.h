// A node's running timed commands (a flash, a burst, a PWM run), kept outside the node for the
// next one: a node killed during a flash must not take the flash's end for a restart (issue #32
// item 6; docs/failsafe.md, "What the node cannot do"). Their ends are kept as absolute seconds
// of a clock that outlives the node: wall-clock time on the parameter server
// (ros/running_timed_parameter.h). ROS-free, so the simulation's harness can keep them the same
// way once its model carries them across a new node (docs/simulation.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "modbus_rtu_driver/devices/failsafe.h"

namespace modbus_rtu_driver {

struct KeptTimedCommand {
  uint8_t channel = 0;
  int during = -1;     // the level until the end: 0 or 1; -1 any (the device toggles it)
  bool after = false;  // the level after the end
  double ends = -1.0;  // absolute seconds
};

// What to keep of `running` (DeviceFailsafe's timed commands at `now`): those with an end.
std::vector<KeptTimedCommand> keepTimedCommands(const std::vector<TimedIntent>& running,
                                                double now);

// What the next node resumes at `now`: those not ended yet on channels below `channels`, with
// the seconds left. One that ended while no node ran is dropped: the first poll shows its end.
std::vector<TimedIntent> resumeTimedCommands(const std::vector<KeptTimedCommand>& kept, double now,
                                             size_t channels);

}  // namespace modbus_rtu_driver
