// The connection the TCP links share.
#include "modbus_rtu_driver/core/link/tcp_link.h"

#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>

#include "modbus_rtu_driver/core/link/tcp_socket.h"

namespace modbus_rtu_driver {

TcpLink::TcpLink(LinkConfig config, LinkTarget target)
    : Link(std::move(config), std::move(target)) {}

TcpLink::~TcpLink() {
  disconnect();
}

bool TcpLink::connect(std::string* error) {
  disconnect();
  fd_ = connectTcp(target_.host, target_.host_port, error);
  if (fd_ < 0) return false;
  noteConnected();
  return true;
}

void TcpLink::disconnect() {
  if (fd_ < 0) return;
  close(fd_);
  fd_ = -1;
}

std::string TcpLink::medium() const {
  return "gateway " + target_.host + ":" + std::to_string(target_.host_port);
}

double TcpLink::responseTimeout(const EncodedRequest& request) const {
  return gatewayResponseTimeout(config_, request.adu().size(), request.replyLength()) +
         reply_delay_[request.request().slave];
}

Result TcpLink::closedUnsent(const Request& request) const {
  return Result::failure(ErrorKind::kIo,
                         request.describe() + ": not sent, " + medium() + " closed the connection");
}

Result TcpLink::send(const Request& request, const Bytes& frame) {
  const auto start = std::chrono::steady_clock::now();
  const double cpu = observingWire() ? wireCpuSeconds() : 0;
  if (sendAll(fd_, frame)) {
    noteWire(true, start, std::chrono::steady_clock::now(), frame, cpu);
    return Result::success();
  }
  return Result::failure(
      ErrorKind::kIo, request.describe() + ": not sent, " + medium() + ": " + std::strerror(errno));
}

}  // namespace modbus_rtu_driver
