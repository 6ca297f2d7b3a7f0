// A TCP client socket to a gateway, as the TCP transports use it.
#pragma once

#include <cstdint>
#include <string>

#include "modbus_rtu_driver/core/modbus/frame.h"

namespace modbus_rtu_driver {

// Seconds a connection attempt may take before it counts as failed.
constexpr double kTcpConnectTimeout = 3.0;

// Connects to host:port (name or address, IPv4 or IPv6) within kTcpConnectTimeout; returns the
// descriptor (blocking, TCP_NODELAY, keep-alive, unacknowledged data failing the connection
// after a few seconds so a gateway that vanished shows as an i/o error), or -1 with a message.
int connectTcp(const std::string& host, int port, std::string* error);
// Writes all of `bytes`; false with errno set when the connection failed (no SIGPIPE).
bool sendAll(int fd, const Bytes& bytes);
// Reads what is waiting without blocking and drops it; returns the byte count, or -1 when the
// peer closed the connection or it failed.
long discardWaiting(int fd);
// True when the peer has closed the connection and nothing it sent before is still unread
// (looked at without reading).
bool closedByPeer(int fd);

}  // namespace modbus_rtu_driver
