// RTU requests carried as MBAP frames (core/modbus/mbap.h).
#include "modbus_rtu_driver/core/link/modbus_tcp_link.h"

#include <chrono>

#include "modbus_rtu_driver/core/link/tcp_socket.h"
#include "modbus_rtu_driver/core/modbus/mbap.h"

namespace modbus_rtu_driver {

namespace {
using Steady = std::chrono::steady_clock;
}  // namespace

// A connection the gateway closed while the bus was idle fails the request unsent (a late reply
// still waiting is read and dropped by its transaction id below).
// The MBAP frame is the encoded request's with this attempt's transaction id (a copy, not a
// second encoding).
Result ModbusTcpLink::attempt(const EncodedRequest& request) {
  if (closedByPeer(fd_)) return closedUnsent(request.request());
  const uint16_t transaction = ++next_transaction_;
  Result sent = send(request.request(), rtuToMbap(transaction, request.adu()));
  if (!sent.ok()) return sent;
  const auto deadline =
      Steady::now() + std::chrono::duration_cast<Steady::duration>(
                          std::chrono::duration<double>(responseTimeout(request)));
  std::string header_error;
  const auto length_of = [&](const Bytes& b) {
    return static_cast<long>(mbapLengthFromHeader(b, &header_error));
  };
  for (;;) {
    const double left = std::chrono::duration<double>(deadline - Steady::now()).count();
    Bytes reply;
    int error = 0;
    const ReadStatus status =
        readObserved(fd_, left, gatewayByteTimeout(config_), length_of, kMbapHeaderLength + 1,
                     kMaxMbapAduLength, &reply, &error);
    if (status == ReadStatus::kComplete && mbapTransaction(reply) != transaction) {
      addStaleBytes(reply.size());  // the late reply to an earlier request
      continue;
    }
    if (status == ReadStatus::kComplete) return decodeReply(request, mbapToRtu(reply));
    Result r = readFailure(request.request(), status, reply, error, medium());
    // Part of a frame read, or a header that is not MBAP: the stream is out of step and only a
    // new connection puts it back (the link reports the answer lost, then reconnects).
    if (!reply.empty() && r.error != ErrorKind::kIo) {
      if (!header_error.empty()) r.message += " (" + header_error + ")";
      r.message += "; reconnecting to resynchronise";
      disconnect();
    }
    return r;
  }
}

// Unit id 0: the gateway broadcasts on its line and nobody answers.
Result ModbusTcpLink::sendBroadcast(const EncodedRequest& request) {
  if (closedByPeer(fd_)) return closedUnsent(request.request());
  return send(request.request(), rtuToMbap(++next_transaction_, request.adu()));
}

namespace {

std::unique_ptr<Link> make(const LinkConfig& config, const LinkTarget& target) {
  return std::make_unique<ModbusTcpLink>(config, target);
}

const LinkType kModbusTcpLink{
    "tcp://",
    "Modbus TCP",
    "tcp://HOST:PORT",
    "tcp://",
    "MBAP frames to a Modbus TCP device or gateway, the device's address as unit id",
    /*networked=*/true,
    /*answers_for_silence=*/true,
    parseHostPort,
    make};
const bool kRegistered = linkTypes().add(kModbusTcpLink);

}  // namespace

}  // namespace modbus_rtu_driver
