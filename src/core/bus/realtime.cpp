#include "modbus_rtu_driver/core/bus/realtime.h"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>

#include <cerrno>
#include <cstring>

namespace modbus_rtu_driver {

namespace {
std::string limitText(int resource) {
  rlimit limit{};
  if (getrlimit(resource, &limit) != 0) return "unknown";
  return limit.rlim_cur == RLIM_INFINITY ? "unlimited" : std::to_string(limit.rlim_cur);
}
}  // namespace

bool raiseToRealtime(int priority, std::string* error) {
  sched_param param{};
  param.sched_priority = priority;
  const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (err == 0) return true;
  if (error)
    *error = "SCHED_FIFO priority " + std::to_string(priority) + " refused: " + std::strerror(err) +
             " (rtprio limit " + limitText(RLIMIT_RTPRIO) +
             "; raise it with `ulimit -r` or /etc/security/limits.conf, or grant CAP_SYS_NICE)";
  return false;
}

bool lockMemory(std::string* error) {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) return true;
  if (error)
    *error = std::string("mlockall refused: ") + std::strerror(errno) + " (memlock limit " +
             limitText(RLIMIT_MEMLOCK) + " bytes; raise it with `ulimit -l` or limits.conf)";
  return false;
}

}  // namespace modbus_rtu_driver
