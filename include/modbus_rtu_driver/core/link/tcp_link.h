// The TCP transports: a link whose frames go through a socket to a gateway (or a Modbus TCP
// device). The base holds the connection; the two forms differ in what they put on it.
//   RtuOverTcpLink (rtu+tcp://): RTU frames as on the wire, for transparent RS485-Ethernet
//     gateways. The serial rules hold on the far side: one transaction at a time, stale bytes
//     dropped before a request, the reply read by its announced length and its CRC checked,
//     the late-reply guard, addresses 0 and 248-255.
//   ModbusTcpLink (tcp://): MBAP frames (core/modbus/mbap.h), the device address as the unit id
//     (0-255); a reply is matched by its transaction id, others (late replies) are dropped.
// Timeouts are the serial line's at `baud` plus network_allowance. A closed or failed
// connection is an i/o error (kIo): the link disconnects and the bus reconnects with backoff.
#pragma once

#include <string>

#include "modbus_rtu_driver/core/link/link.h"

namespace modbus_rtu_driver {

class TcpLink : public Link {
 public:
  explicit TcpLink(LinkConfig config);
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

 private:
  PortAddress address_;
};

class RtuOverTcpLink : public TcpLink {
 public:
  using TcpLink::TcpLink;
  PortKind kind() const override { return PortKind::kRtuOverTcp; }

 protected:
  Result attempt(const EncodedRequest& request) override;
  Result sendBroadcast(const EncodedRequest& request) override;

 private:
  bool prepareLine(const EncodedRequest& request);  // false: the connection is gone
};

class ModbusTcpLink : public TcpLink {
 public:
  using TcpLink::TcpLink;
  PortKind kind() const override { return PortKind::kModbusTcp; }

 protected:
  Result attempt(const EncodedRequest& request) override;
  Result sendBroadcast(const EncodedRequest& request) override;
  double minGap() const override { return 0; }  // the gateway paces its own line

 private:
  uint16_t next_transaction_ = 0;
};

}  // namespace modbus_rtu_driver
