// A pseudo-terminal for link tests: the code under test opens `path()` like a serial port, the
// test plays the device on the master side.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <string>

#include "modbus_rtu_driver/core/modbus/frame.h"

namespace modbus_rtu_driver {

class PtyPair {
 public:
  PtyPair() {
    master_ = posix_openpt(O_RDWR | O_NOCTTY);
    grantpt(master_);
    unlockpt(master_);
    path_ = ptsname(master_);
    // Hold the slave side open so the line survives the client closing it.
    slave_ = open(path_.c_str(), O_RDWR | O_NOCTTY);
    termios tio{};
    tcgetattr(slave_, &tio);
    cfmakeraw(&tio);
    tcsetattr(slave_, TCSANOW, &tio);
  }
  ~PtyPair() {
    close(slave_);
    close(master_);
  }
  const std::string& path() const { return path_; }

  // Reads what the client sent: stops at `count` bytes or after `timeout_ms` of silence.
  Bytes read(size_t count, int timeout_ms = 1000) {
    Bytes out;
    while (out.size() < count) {
      pollfd p{master_, POLLIN, 0};
      if (poll(&p, 1, timeout_ms) <= 0) break;
      uint8_t buf[256];
      const ssize_t n = ::read(master_, buf, std::min(sizeof buf, count - out.size()));
      if (n <= 0) break;
      out.insert(out.end(), buf, buf + n);
    }
    return out;
  }
  void write(const Bytes& bytes) {
    if (!bytes.empty() && ::write(master_, bytes.data(), bytes.size()) < 0) return;
  }
  // Bytes written on the master side that have reached the client's input queue and are not
  // read yet. A pty hands written bytes on through a kernel worker, a moment later: a test that
  // needs them to be there before the client acts waits for this instead of sleeping.
  size_t pendingAtClient() const {
    int n = 0;
    return ioctl(slave_, FIONREAD, &n) == 0 && n > 0 ? static_cast<size_t>(n) : 0;
  }

 private:
  int master_ = -1, slave_ = -1;
  std::string path_;
};

}  // namespace modbus_rtu_driver
