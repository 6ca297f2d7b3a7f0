#include "modbus_rtu_driver/core/port_claim.h"

#include <modbus/modbus.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <termios.h>

#include <cerrno>

namespace modbus_rtu_driver {

bool claimPort(int fd, const std::string& port, std::string* error) {
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    if (error) *error = port + " is in use by another process (it holds the port's lock)";
    return false;
  }
  // Not every descriptor is a tty (a socket in tests): exclusivity is then simply not offered.
  (void)ioctl(fd, TIOCEXCL);
  return true;
}

void releasePort(int fd) {
  if (fd >= 0) (void)ioctl(fd, TIOCNXCL);
}

std::string openError(const std::string& port, int err) {
  if (err == EBUSY) return port + " is in use by another process (it has the port exclusively)";
  return "cannot open " + port + ": " + modbus_strerror(err);
}

}  // namespace modbus_rtu_driver
