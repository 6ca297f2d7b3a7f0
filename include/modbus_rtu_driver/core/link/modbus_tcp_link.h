// The Modbus TCP link (tcp://): MBAP frames (core/modbus/mbap.h), the device address as the unit
// id (0-255); a reply is matched by its transaction id, others (late replies) are dropped.
#pragma once

#include "modbus_rtu_driver/core/link/tcp_link.h"

namespace modbus_rtu_driver {

class ModbusTcpLink : public TcpLink {
 public:
  using TcpLink::TcpLink;

 protected:
  Result attempt(const EncodedRequest& request) override;
  Result sendBroadcast(const EncodedRequest& request) override;
  double minGap() const override { return 0; }               // the gateway paces its own line
  bool guardsLateReplies() const override { return false; }  // MBAP ids tell replies apart

 private:
  uint16_t next_transaction_ = 0;
};

}  // namespace modbus_rtu_driver
