#include "modbus_rtu_driver/core/link/rtu_over_tcp_link.h"

#include "modbus_rtu_driver/core/link/tcp_socket.h"

namespace modbus_rtu_driver {

// The late-reply guard and the gap, as on a serial port; then what is waiting (a late reply,
// the gateway's noise) belongs to nobody.
bool RtuOverTcpLink::prepareLine(const EncodedRequest& request) {
  settleLine(fd_, request);
  keepGap();
  const long stale = discardWaiting(fd_);
  if (stale < 0) return false;
  addStaleBytes(static_cast<uint64_t>(stale));
  return true;
}

Result RtuOverTcpLink::attempt(const EncodedRequest& request) {
  if (!prepareLine(request)) return closedUnsent(request.request());
  Result sent = send(request.request(), request.adu());
  if (!sent.ok()) return sent;
  return readRtuReply(fd_, request, gatewayByteTimeout(config_), medium());
}

Result RtuOverTcpLink::sendBroadcast(const EncodedRequest& request) {
  if (!prepareLine(request)) return closedUnsent(request.request());
  return send(request.request(), request.adu());
}

namespace {

std::unique_ptr<Link> make(const LinkConfig& config, const LinkTarget& target) {
  return std::make_unique<RtuOverTcpLink>(config, target);
}

const LinkType kRtuOverTcpLink{
    "rtu+tcp://",
    "RTU over TCP",
    "rtu+tcp://HOST:PORT",
    "rtu+tcp://",
    "RTU frames, byte for byte, through a transparent RS485-Ethernet gateway",
    /*networked=*/true,
    /*answers_for_silence=*/false,
    parseHostPort,
    make};
const bool kRegistered = linkTypes().add(kRtuOverTcpLink);

}  // namespace

}  // namespace modbus_rtu_driver
