#include "modbus_rtu_driver/core/server/share_gateway.h"

#include <thread>

namespace modbus_rtu_driver {

uint8_t shareExceptionFor(const Result& result) {
  if (result.error == ErrorKind::kException) return result.exception_code;
  if (answerLost(result.error)) return kGatewayTargetFailed;
  if (result.error == ErrorKind::kInvalidArgument) return kIllegalDataValue;
  return kGatewayPathUnavailable;  // kIo, kNotConnected: no way to the device
}

Bytes shareReplyFor(const Request& request, const Result& result) {
  if (result.ok()) return encodeReply(request, result.values);
  return encodeException(request.slave, static_cast<uint8_t>(request.function),
                         shareExceptionFor(result));
}

ShareGateway::ShareGateway(BusScheduler& scheduler, ShareConfig config,
                           std::function<std::string(uint8_t)> device_of)
    : scheduler_(scheduler), config_(std::move(config)), device_of_(std::move(device_of)) {
  // The server refuses writes before decoding them: a malformed write gets 01 too, not the
  // 02 / 03 its fields would earn (docs/share.md).
  config_.server.refuse_writes = config_.read_only;
  server_ = std::make_unique<ModbusTcpServer>(
      config_.server, [this](const ModbusTcpServer::Incoming& in) { handle(in); });
}

ShareGateway::~ShareGateway() {
  stop();
}

bool ShareGateway::start(std::string* error) {
  if (config_.max_queue < 1) {
    if (error) *error = "max_queue: must be at least 1";
    return false;
  }
  if (!(config_.broadcast_turnaround >= 0 &&
        config_.broadcast_turnaround <= kMaxBroadcastTurnaround)) {
    if (error)
      *error = "broadcast_turnaround: " + std::to_string(config_.broadcast_turnaround) +
               " s is outside 0-1 s";
    return false;
  }
  scheduler_.openShared();
  return server_->start(error);
}

// No new request (the server stops first), then none of the queued ones: the node calls this
// before its safe writes at shutdown, and a client's write that ran after them would undo them.
void ShareGateway::stop() {
  server_->stop();
  scheduler_.closeShared("the share stopped (the node is stopping)");
}

// On the server's thread: never waits for the bus.
void ShareGateway::handle(const ModbusTcpServer::Incoming& in) {
  const Request& request = in.request;
  if (++in_flight_ > config_.max_queue) {
    --in_flight_;
    return server_->replyException(in, kSlaveDeviceBusy);
  }
  const Request sent = forwarded(request);
  const std::string device = device_of_ ? device_of_(request.slave) : "";
  const auto turnaround = std::chrono::duration<double>(
      sent.slave == kBroadcastAddress ? config_.broadcast_turnaround : 0.0);
  scheduler_.submitShared(
      device,
      [this, sent, turnaround](Transport& t) {
        Result r = t.execute(sent);
        if (!isReadFunction(sent.function) && wrote_) wrote_(sent, r);
        // On the bus thread, on purpose: nothing else may go on the line during the delay.
        if (r.ok() && turnaround.count() > 0) std::this_thread::sleep_for(turnaround);
        return r;
      },
      [this, in](const Result& r) {
        server_->reply(in, shareReplyFor(in.request, r));
        --in_flight_;
      });
}

}  // namespace modbus_rtu_driver
