// One owner per serial port: the bus node, the slave role and the commissioning tool take a
// port the same way.
#pragma once

#include <string>

namespace modbus_rtu_driver {

// Claims the open port `fd` (named `port` in messages) for this process alone:
//  - flock(LOCK_EX): another program of this project, or any that honours the lock, is told the
//    port is in use;
//  - TIOCEXCL: the kernel refuses every further open() of the tty (EBUSY), so a program that
//    ignores locks (mbpoll, a terminal, `cat`) cannot take bytes meant for us. Root can still
//    open it (the kernel lets CAP_SYS_ADMIN through), and programs that opened it before us keep
//    their descriptors.
// False with a message when another process holds the lock.
bool claimPort(int fd, const std::string& port, std::string* error);
// Gives the port back before it is closed: others may open it again even if another descriptor
// (a simulator's, a pty's other holder) keeps the tty alive. The lock goes with the close.
void releasePort(int fd);
// The message for a port that could not be opened with `err` (errno): EBUSY means that another
// process holds it exclusively.
std::string openError(const std::string& port, int err);

}  // namespace modbus_rtu_driver
