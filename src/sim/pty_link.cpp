#include "modbus_rtu_driver/sim/pty_link.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstring>
#include <string>

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

std::string readAll(int fd) {
  std::string text;
  char buf[64];
  ssize_t n = 0;
  while ((n = pread(fd, buf, sizeof buf, static_cast<off_t>(text.size()))) > 0)
    text.append(buf, static_cast<size_t>(n));
  return text;
}

std::string targetOf(const std::string& link) {
  char buf[PATH_MAX];
  const ssize_t n = readlink(link.c_str(), buf, sizeof buf - 1);
  return n > 0 ? std::string(buf, static_cast<size_t>(n)) : std::string();
}

}  // namespace

// The lock is taken before the link is touched. A holder that stops removes the lock file while
// it holds the lock, so a lock taken on a file no longer at the path is given up and taken again.
bool PtyLink::lock(const std::string& link, std::string* error) {
  const std::string path = link + ".lock";
  for (int attempt = 0; attempt < 10; ++attempt) {
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) {
      if (error) *error = "cannot create " + path + ": " + std::strerror(errno);
      return false;
    }
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      std::string pid = readAll(fd);
      while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
      ::close(fd);
      if (error)
        *error = err == EWOULDBLOCK
                     ? link + " belongs to a running simulator (pid " +
                           (pid.empty() ? std::string("unknown") : pid) + ", which holds " + path +
                           "): give each simulator its own --link"
                     : "cannot lock " + path + ": " + std::strerror(err);
      return false;
    }
    struct stat held {
    }, there{};
    if (fstat(fd, &held) == 0 && stat(path.c_str(), &there) == 0 && held.st_dev == there.st_dev &&
        held.st_ino == there.st_ino) {
      const std::string pid = std::to_string(getpid()) + "\n";
      // The pid only makes a refusal's message richer: the lock itself is what counts.
      const bool written = ftruncate(fd, 0) == 0 && pwrite(fd, pid.data(), pid.size(), 0) ==
                                                        static_cast<ssize_t>(pid.size());
      (void)written;
      lock_fd_ = fd;
      lock_path_ = path;
      return true;
    }
    ::close(fd);  // the previous holder removed it as we opened it: try the new one
  }
  if (error) *error = "cannot lock " + path + ": it keeps being replaced";
  return false;
}

bool PtyLink::open(const std::string& link, int baud, std::string* error, Parity parity) {
  auto fail = [&](const std::string& what) {
    if (error) *error = what + ": " + std::strerror(errno);
    close();
    return false;
  };
  const size_t slash = link.find_last_of('/');
  if (slash != std::string::npos && slash > 0 && !makeDirs(link.substr(0, slash)))
    return fail("cannot create the directory of " + link);
  if (!lock(link, error)) {
    close();
    return false;
  }
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
  unlink(link.c_str());  // a stale link: whoever made it is gone (it held no lock)
  if (symlink(pts.c_str(), link.c_str()) != 0) return fail("cannot link " + link);
  link_ = link;
  pts_ = pts;
  return true;
}

void PtyLink::close() {
  // Only what this object made: the link while it still points to our pty, then the lock file
  // (removed while still held, see lock()). The link goes before the pty: once the pty is
  // closed and the program on the other side closes it too, the kernel gives its number to the
  // next pty made, maybe another simulator's. A program reopening our link in between (the bus
  // node reconnects with backoff) would open that other pty and take its lock, and the other
  // simulator's node is refused its port. The likeliest cause of issue 49's load failures: with
  // two rostests side by side, a launch test's node was refused its new pty for 30 s, the holder
  // named another test's bus node.
  if (!link_.empty() && targetOf(link_) == pts_) unlink(link_.c_str());
  link_.clear();
  pts_.clear();
  for (int* fd : {&slave_fd_, &master_fd_}) {
    if (*fd >= 0) ::close(*fd);
    *fd = -1;
  }
  if (lock_fd_ >= 0) {
    unlink(lock_path_.c_str());
    ::close(lock_fd_);
  }
  lock_fd_ = -1;
  lock_path_.clear();
}

bool PtyLink::claimed() const {
  if (slave_fd_ < 0) return false;
  // flock is per file: our own descriptor of the slave side conflicts with the program's.
  if (flock(slave_fd_, LOCK_SH | LOCK_NB) != 0) return errno == EWOULDBLOCK;
  flock(slave_fd_, LOCK_UN);
  return false;
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
