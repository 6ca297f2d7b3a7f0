// The RTU-over-TCP link (rtu+tcp://): RTU frames as on the wire, for transparent RS485-Ethernet
// gateways. The serial rules hold on the far side: one transaction at a time, stale bytes
// dropped before a request, the reply read by its announced length and its CRC checked, the
// late-reply guard, addresses 0 and 248-255.
#pragma once

#include "modbus_rtu_driver/core/link/tcp_link.h"

namespace modbus_rtu_driver {

class RtuOverTcpLink : public TcpLink {
 public:
  using TcpLink::TcpLink;

 protected:
  Result attempt(const EncodedRequest& request) override;
  Result sendBroadcast(const EncodedRequest& request) override;

 private:
  bool prepareLine(const EncodedRequest& request);  // false: the connection is gone
};

}  // namespace modbus_rtu_driver
