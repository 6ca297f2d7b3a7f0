#include "modbus_rtu_driver/core/link/serial_port.h"

#include <modbus/modbus.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <termios.h>

#include <cerrno>
#include <chrono>
#include <cmath>

namespace modbus_rtu_driver {

modbus_t* openSerialPort(const LinkConfig& link, std::string* error) {
  modbus_t* ctx = modbus_new_rtu(link.port.c_str(), link.baud, parityLetter(link.parity),
                                 link.data_bits, link.stop_bits);
  if (!ctx) {
    if (error) *error = "cannot use " + link.port + ": " + modbus_strerror(errno);
    return nullptr;
  }
  if (modbus_connect(ctx) == -1) {
    if (error) *error = openError(link.port, errno);
    modbus_free(ctx);
    return nullptr;
  }
  // One owner per port: two drivers on one bus would answer each other's requests.
  if (!claimPort(modbus_get_socket(ctx), link.port, error)) {
    closeSerialPort(ctx);
    return nullptr;
  }
  return ctx;
}

void closeSerialPort(modbus_t* ctx) {
  if (!ctx) return;
  releasePort(modbus_get_socket(ctx));
  modbus_close(ctx);
  modbus_free(ctx);
}

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
