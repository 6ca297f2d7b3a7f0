#include "modbus_rtu_driver/core/link/serial_port.h"

#include <modbus/modbus.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <termios.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

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

std::string lockHolder(int fd) {
  struct stat st {};
  if (fstat(fd, &st) != 0) return {};
  // fs/locks.c writes the file as "MAJOR:MINOR:INODE", the device numbers in hex (two digits at
  // least), the inode in decimal.
  char file[64];
  std::snprintf(file, sizeof file, "%02x:%02x:%lu", major(st.st_dev), minor(st.st_dev),
                static_cast<unsigned long>(st.st_ino));
  std::ifstream locks("/proc/locks");
  std::string line;
  while (std::getline(locks, line)) {
    // "1: FLOCK  ADVISORY  WRITE 2463 00:19:4 0 EOF"; a waiter's line has "->" after the number.
    std::istringstream words(line);
    std::string number, kind, mode, access, pid, where;
    if (!(words >> number >> kind >> mode >> access >> pid >> where) || kind != "FLOCK" ||
        where != file)
      continue;
    std::ifstream comm_file("/proc/" + pid + "/comm");
    std::string comm;
    std::getline(comm_file, comm);
    return "pid " + pid + (comm.empty() ? "" : ", " + comm);
  }
  return {};
}

bool claimPort(int fd, const std::string& port, std::string* error) {
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    if (!error) return false;
    if (err != EWOULDBLOCK) {
      *error = "cannot lock " + port + ": " + std::strerror(err);
      return false;
    }
    // Who it is tells the user what to stop (another node, the commissioning tool, a simulator).
    const std::string holder = lockHolder(fd);
    *error = port + " is in use by another process (" + (holder.empty() ? "it" : holder + ",") +
             " holds the port's lock)";
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
