// The base of the TCP links: a link whose frames go through a socket to a gateway (or a Modbus
// TCP device). It holds the connection; its two forms differ in what they put on it:
// RtuOverTcpLink (rtu_over_tcp_link.h) and ModbusTcpLink (modbus_tcp_link.h).
// Timeouts are the serial line's at `baud` plus network_allowance. A closed or failed
// connection is an i/o error (kIo): the link disconnects and the bus reconnects with backoff.
#pragma once

#include <string>

#include "modbus_rtu_driver/core/link/link.h"

namespace modbus_rtu_driver {

class TcpLink : public Link {
 public:
  explicit TcpLink(LinkConfig config, LinkTarget target = {});
  ~TcpLink() override;
  bool connect(std::string* error) override;
  bool connected() const override { return fd_ >= 0; }
  void disconnect() override;

 protected:
  double responseTimeout(const EncodedRequest& request) const override;
  // Sends `frame` (the request's, or its MBAP form); a failure is kIo (not sent, or the
  // connection is gone).
  Result send(const Request& request, const Bytes& frame);
  std::string medium() const;  // "gateway HOST:PORT"
  // The failure of a request found the connection closed before it was sent.
  Result closedUnsent(const Request& request) const;

  int fd_ = -1;
};

}  // namespace modbus_rtu_driver
