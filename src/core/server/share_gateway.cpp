#include "modbus_rtu_driver/core/server/share_gateway.h"

#include <algorithm>
#include <thread>

#include "modbus_rtu_driver/core/config/number_text.h"

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
                           std::function<std::string(uint8_t)> device_of,
                           TransactionTime transaction_time, Clock& clock)
    : scheduler_(scheduler),
      config_(std::move(config)),
      device_of_(std::move(device_of)),
      transaction_time_(std::move(transaction_time)),
      clock_(clock) {
  // The server refuses writes before decoding them: a malformed write gets 01 too, not the
  // 02 / 03 its fields would earn (docs/share.md).
  config_.server.refuse_writes = config_.read_only;
  server_ = std::make_unique<ModbusTcpServer>(
      config_.server, [this](const ModbusTcpServer::Incoming& in) { handle(in); });
}

ShareGateway::~ShareGateway() {
  stop();
}

double ShareGateway::longestTransaction() const {
  if (!transaction_time_) return 0.0;
  double longest = 0.0;
  // The largest requests and replies (256-byte ADUs), to every unit a client may name: a
  // device's reply delay (an LD58A08's) lengthens its address's response timeout.
  constexpr int kLastUnit = 255;
  for (int unit = 1; unit <= kLastUnit; ++unit) {
    const auto slave = static_cast<uint8_t>(unit);
    longest = std::max({longest, transaction_time_(Request::readHoldingRegisters(slave, 0, 125)),
                        transaction_time_(Request::readCoils(slave, 0, 2000)),
                        transaction_time_(Request::writeMultipleRegisters(
                            slave, 0, std::vector<uint16_t>(123, 0)))});
  }
  return std::max(longest, ownTransaction(Request::writeMultipleRegisters(
                               kBroadcastAddress, 0, std::vector<uint16_t>(123, 0))));
}

double ShareGateway::ownTransaction(const Request& sent) const {
  return transaction_time_(sent) +
         (sent.slave == kBroadcastAddress ? config_.broadcast_turnaround : 0.0);
}

bool ShareGateway::start(std::string* error) {
  return open(error) && server_->start(error);
}

bool ShareGateway::open(std::string* error) {
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
  if (transaction_time_) {
    const double longest = longestTransaction();
    if (config_.answer_within > 0 && config_.answer_within < longest) {
      if (error)
        *error = "answer_within: " + numberText(config_.answer_within) +
                 " s is shorter than the longest transaction a client's request can take on "
                 "this bus (" +
                 numberText(longest) +
                 " s: the largest request and reply with every retry and the late-reply "
                 "guard); make it at least that, or lower response_timeout or retries";
      return false;
    }
    bound_ = config_.answer_within > 0 ? config_.answer_within : 2.0 * longest;
    {
      std::lock_guard<std::mutex> lock(deadlines_mutex_);
      stopping_ = false;
    }
    if (!expiry_thread_.joinable()) expiry_thread_ = std::thread([this] { expireLoop(); });
  }
  scheduler_.openShared();
  return true;
}

// No new request (the server stops first), then none of the queued ones: the node calls this
// before its safe writes at shutdown, and a client's write that ran after them would undo them.
void ShareGateway::stop() {
  server_->stop();
  scheduler_.closeShared("the share stopped (the node is stopping)");
  {
    std::lock_guard<std::mutex> lock(deadlines_mutex_);
    stopping_ = true;
    deadlines_.clear();
  }
  clock_.notifyAll(deadlines_cv_);
  if (expiry_thread_.joinable()) expiry_thread_.join();
}

void ShareGateway::expire(Waiting& w) {
  int queued = Waiting::kQueued;
  if (!w.state.compare_exchange_strong(queued, Waiting::kExpired)) return;
  ++expired_;
  w.answer(encodeException(w.request.slave, static_cast<uint8_t>(w.request.function),
                           kGatewayTargetFailed));
}

void ShareGateway::expireLoop() {
  std::unique_lock<std::mutex> lock(deadlines_mutex_);
  while (!stopping_) {
    const Clock::time_point next =
        deadlines_.empty() ? Clock::time_point::max() : deadlines_.begin()->first;
    if (next > clock_.now()) {
      clock_.waitUntil(lock, deadlines_cv_, next);
      continue;
    }
    const std::shared_ptr<Waiting> w = deadlines_.begin()->second;
    deadlines_.erase(deadlines_.begin());
    lock.unlock();
    expire(*w);
    lock.lock();
  }
}

// On the server's thread.
void ShareGateway::handle(const ModbusTcpServer::Incoming& in) {
  forward(in.request, [this, in](const Bytes& rtu_adu) { server_->reply(in, rtu_adu); });
}

void ShareGateway::forward(const Request& request, Answer answer,
                           std::function<void(const Result&)> ran, uint64_t tag) {
  if (++in_flight_ > config_.max_queue) {
    --in_flight_;
    return answer(
        encodeException(request.slave, static_cast<uint8_t>(request.function), kSlaveDeviceBusy));
  }
  const Request sent = forwarded(request);
  const std::string device = device_of_ ? device_of_(request.slave) : "";
  const auto turnaround = std::chrono::duration<double>(
      sent.slave == kBroadcastAddress ? config_.broadcast_turnaround : 0.0);
  auto w = std::make_shared<Waiting>();
  w->request = request;
  w->answer = std::move(answer);
  const bool bounded = bound_ > 0;
  if (bounded) {
    // The latest start that still ends within the bound.
    w->start_by = clock_.now() + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>(bound_ - ownTransaction(sent)));
    bool earliest = false;  // the expiry thread sleeps until the earliest: wake it only then
    {
      std::lock_guard<std::mutex> lock(deadlines_mutex_);
      earliest = deadlines_.empty() || w->start_by < deadlines_.begin()->first;
      deadlines_.emplace(w->start_by, w);
    }
    if (earliest) clock_.notifyAll(deadlines_cv_);
  }
  scheduler_.submitShared(
      device,
      [this, sent, turnaround, w, bounded, ran = std::move(ran)](Transport& t) {
        // Too late to be answered in time (the expiry thread may not have run yet): 0B, unsent.
        if (bounded && clock_.now() > w->start_by) expire(*w);
        int queued = Waiting::kQueued;
        if (!w->state.compare_exchange_strong(queued, Waiting::kRunning))
          return Result::failure(ErrorKind::kInvalidArgument,
                                 sent.describe() +
                                     ": not sent: it could not start within the share's "
                                     "answer bound (answered 0B)");
        Result r = t.execute(sent);
        if (r.retry_owed) {
          // A read cut short in another device's late-reply guard: queued again for its
          // retries (BusScheduler::useGuardTime), which must start by the same latest start to
          // end within the bound; else 0B now, or from the expiry thread at that start.
          int running = Waiting::kRunning;
          w->state.compare_exchange_strong(running, Waiting::kQueued);
          if (bounded && clock_.now() > w->start_by) expire(*w);
          return r;
        }
        if (!isReadFunction(sent.function) && wrote_) wrote_(sent, r);
        if (ran) ran(r);
        // On the bus thread, on purpose: nothing else may go on the line during the delay.
        if (r.ok() && turnaround.count() > 0) std::this_thread::sleep_for(turnaround);
        return r;
      },
      [this, w](const Result& r) {
        // Ran: its answer. Refused unsent (the share stopped, the port closed) while queued:
        // that answer, unless the bound's 0B went first.
        int queued = Waiting::kQueued;
        if (w->state.load() == Waiting::kRunning ||
            w->state.compare_exchange_strong(queued, Waiting::kDone))
          w->answer(shareReplyFor(w->request, r));
        --in_flight_;
      },
      tag, sent);
}

}  // namespace modbus_rtu_driver
