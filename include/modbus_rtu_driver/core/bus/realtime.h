// Real-time scheduling for the bus thread: a relay command waits behind whatever else the
// machine runs unless the thread that owns the line may preempt it. Optional, and granted only
// where the user's rtprio limit (or CAP_SYS_NICE) allows; docs/ros_api.md says when to use it.
#pragma once

#include <string>

namespace modbus_rtu_driver {

// Puts the calling thread in SCHED_FIFO at `priority` (1-99). False with a message naming the
// limit to raise when the kernel refuses (RLIMIT_RTPRIO, e.g. `ulimit -r` or limits.conf).
bool raiseToRealtime(int priority, std::string* error);
// Locks the process's pages in memory (mlockall, current and future), so a page fault never
// stalls the bus thread. False with a message naming RLIMIT_MEMLOCK when refused.
bool lockMemory(std::string* error);

}  // namespace modbus_rtu_driver
