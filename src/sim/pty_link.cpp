#include "modbus_rtu_driver/sim/pty_link.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace modbus_rtu_driver {

namespace {

int baudOf(speed_t s) {
  switch (s) {
    case B1200:
      return 1200;
    case B2400:
      return 2400;
    case B4800:
      return 4800;
    case B9600:
      return 9600;
    case B19200:
      return 19200;
    case B38400:
      return 38400;
    case B57600:
      return 57600;
    case B115200:
      return 115200;
    default:
      return 0;
  }
}

speed_t speedOf(int baud) {
  switch (baud) {
    case 1200:
      return B1200;
    case 2400:
      return B2400;
    case 4800:
      return B4800;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    default:
      return B9600;
  }
}

// mkdir -p
bool makeDirs(const std::string& path) {
  size_t at = 0;
  do {
    at = path.find('/', at + 1);
    const std::string dir = path.substr(0, at);
    if (mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST) return false;
  } while (at != std::string::npos);
  return true;
}

}  // namespace

bool PtyLink::open(const std::string& link, int baud, std::string* error, Parity parity) {
  auto fail = [&](const std::string& what) {
    if (error) *error = what + ": " + std::strerror(errno);
    close();
    return false;
  };
  master_fd_ = posix_openpt(O_RDWR | O_NOCTTY);
  if (master_fd_ < 0 || grantpt(master_fd_) != 0 || unlockpt(master_fd_) != 0)
    return fail("cannot create a pseudo-terminal");
  const std::string pts = ptsname(master_fd_);
  slave_fd_ = ::open(pts.c_str(), O_RDWR | O_NOCTTY);
  if (slave_fd_ < 0) return fail("cannot open " + pts);
  termios tio{};
  tcgetattr(slave_fd_, &tio);
  cfmakeraw(&tio);
  cfsetispeed(&tio, speedOf(baud));
  cfsetospeed(&tio, speedOf(baud));
  if (parity != Parity::kNone) {
    tio.c_cflag |= PARENB | (parity == Parity::kOdd ? PARODD : 0);
    tio.c_iflag |= INPCK;
  }
  tcsetattr(slave_fd_, TCSANOW, &tio);
  fcntl(master_fd_, F_SETFL, O_NONBLOCK);
  const size_t slash = link.find_last_of('/');
  if (slash != std::string::npos && slash > 0 && !makeDirs(link.substr(0, slash)))
    return fail("cannot create the directory of " + link);
  unlink(link.c_str());
  if (symlink(pts.c_str(), link.c_str()) != 0) return fail("cannot link " + link);
  link_ = link;
  return true;
}

void PtyLink::close() {
  for (int* fd : {&slave_fd_, &master_fd_}) {
    if (*fd >= 0) ::close(*fd);
    *fd = -1;
  }
  if (!link_.empty()) unlink(link_.c_str());
  link_.clear();
}

SimLineSettings PtyLink::lineSettings() const {
  termios tio{};
  SimLineSettings l;
  if (tcgetattr(slave_fd_, &tio) != 0) return l;
  l.baud = baudOf(cfgetospeed(&tio));
  // Linux forces CS8 and clears PARENB on a pty; INPCK (parity checking, which libmodbus sets
  // for even and odd) and PARODD survive, so they tell the parity.
  const bool parity = (tio.c_cflag & PARENB) || (tio.c_iflag & INPCK);
  l.parity = !parity ? Parity::kNone : (tio.c_cflag & PARODD) ? Parity::kOdd : Parity::kEven;
  const tcflag_t size = tio.c_cflag & CSIZE;
  l.data_bits = size == CS5 ? 5 : size == CS6 ? 6 : size == CS7 ? 7 : 8;
  l.stop_bits = (tio.c_cflag & CSTOPB) ? 2 : 1;
  return l;
}

}  // namespace modbus_rtu_driver
