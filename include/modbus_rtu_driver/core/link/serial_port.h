// A serial port, opened and claimed one way by the bus link, the slave role and the
// commissioning tool (one owner per port).
#pragma once

#include <string>

#include "modbus_rtu_driver/core/config/link_config.h"

typedef struct _modbus modbus_t;  // NOLINT: libmodbus's own name

namespace modbus_rtu_driver {

// Opens `link.port` through libmodbus at the link's baud, parity, data and stop bits and claims
// it (claimPort). Null with a message naming the port when it cannot.
modbus_t* openSerialPort(const LinkConfig& link, std::string* error);
// Gives the claim back, closes and frees `ctx` (null is fine).
void closeSerialPort(modbus_t* ctx);

// Claims the open port `fd` (named `port` in messages) for this process alone:
//  - flock(LOCK_EX): another program of this project, or any that honours the lock, is told the
//    port is in use;
//  - TIOCEXCL: the kernel refuses every further open() of the tty (EBUSY), so a program that
//    ignores locks (mbpoll, a terminal, `cat`) cannot take bytes meant for us. Root can still
//    open it (the kernel lets CAP_SYS_ADMIN through), and programs that opened it before us keep
//    their descriptors.
// False with a message when another process holds the lock: it names that process when Linux
// tells (lockHolder).
bool claimPort(int fd, const std::string& port, std::string* error);
// The process that holds the flock of `fd`'s file, from /proc/locks: "pid N, NAME", or empty
// when none is listed (no lock, or /proc unreadable).
std::string lockHolder(int fd);
// Gives the port back before it is closed: others may open it again even if another descriptor
// (a simulator's, a pty's other holder) keeps the tty alive. The lock goes with the close.
void releasePort(int fd);
// The message for a port that could not be opened with `err` (errno): EBUSY means that another
// process holds it exclusively.
std::string openError(const std::string& port, int err);

}  // namespace modbus_rtu_driver
