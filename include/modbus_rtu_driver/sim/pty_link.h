// A pseudo-terminal with its slave side linked at a path, so a program opens it like a serial
// port. The slave side stays open here: the line survives the other program closing it, and its
// termios (which that program sets) tells the line's baud and parity.
//
// One program per link: LINK.lock beside the link is flock'ed (and holds the pid) while the link
// lives, so a second simulator given the same --link is refused instead of replacing the running
// one's link (and deleting it when it stops). On close only what this object made goes: the link
// while it still points to this pty, and the lock file.
#pragma once

#include <string>

#include "modbus_rtu_driver/sim/sim_device.h"

namespace modbus_rtu_driver {

class PtyLink {
 public:
  PtyLink() = default;
  ~PtyLink() { close(); }
  PtyLink(const PtyLink&) = delete;
  PtyLink& operator=(const PtyLink&) = delete;

  // Creates the pty (raw, 8 data bits, 1 stop bit, at `baud` and `parity` N/E/O) and the link
  // (and its directory), replacing a stale link. False with a message, also when the link
  // belongs to a running program (its LINK.lock is held).
  bool open(const std::string& link, int baud, std::string* error, Parity parity = Parity::kNone);
  void close();
  int fd() const { return master_fd_; }  // non-blocking master side
  // What the program on the other side set last (tcgetattr on the slave side we hold open).
  // A Linux pty keeps the speed, PARODD, CSTOPB and INPCK but forces CS8 and clears PARENB:
  // parity counts as on when PARENB or INPCK is set (libmodbus sets INPCK for even and odd; a
  // client that sets only PARENB for even parity is seen as 8N1); data bits read as 8.
  SimLineSettings lineSettings() const;
  // Whether a program on the other side holds the port's lock (the bus node takes flock on the
  // port it opens: serial_port.cpp); any thread. While it does not, the lock is taken for an
  // instant: a program opening the port just then is refused and opens it again.
  bool claimed() const;

 private:
  bool lock(const std::string& link, std::string* error);

  int master_fd_ = -1, slave_fd_ = -1;
  int lock_fd_ = -1;
  std::string link_, pts_, lock_path_;
};

}  // namespace modbus_rtu_driver
