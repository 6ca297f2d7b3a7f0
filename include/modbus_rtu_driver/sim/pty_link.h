// A pseudo-terminal with its slave side linked at a path, so a program opens it like a serial
// port. The slave side stays open here: the line survives the other program closing it, and its
// termios (which that program sets) tells the line's baud and parity.
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

  // Creates the pty (raw, at `baud`) and the link (and its directory). False with a message.
  bool open(const std::string& link, int baud, std::string* error);
  void close();
  int fd() const { return master_fd_; }  // non-blocking master side
  SimLineSettings lineSettings() const;

 private:
  int master_fd_ = -1, slave_fd_ = -1;
  std::string link_;
};

}  // namespace modbus_rtu_driver
