#include "modbus_rtu_driver/runtime/bus_runtime.h"

#include <algorithm>

#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/devices/registry.h"

namespace modbus_rtu_driver {

namespace {

bool isReady(const std::future<Result>& f) {
  return !f.valid() || f.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
}

Clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

BusRuntime::BusRuntime(BusConfig config, Transport& transport, Options options)
    : config_(std::move(config)), options_(std::move(options)), clock_(*options_.clock) {
  scheduler_ = std::make_unique<BusScheduler>(transport, options_.scheduling, clock_);
  double shortest = 0.5;
  bool deadlines = false;  // no heartbeat and no command timeout: nothing to check
  if (!config_.heartbeat_topic.empty()) {
    bus_heartbeat_ = std::make_unique<Watchdog>(config_.heartbeat_timeout, clock_);
    shortest = std::min(shortest, config_.heartbeat_timeout);
    deadlines = true;
  }
  for (const DeviceConfig& dc : config_.devices) {
    // The registered class of its type; dc was checked as it was parsed.
    auto unit = std::make_unique<DeviceUnit>(createDevice(dc), *scheduler_, clock_);
    if (options_.link) options_.link->setReplyDelay(unit->address(), dc.reply_delay);
    scheduler_->addDevice(dc.name);
    DeviceFailsafe& fs = unit->failsafe();
    fs.setBusHeartbeat(bus_heartbeat_.get(), config_.heartbeat_topic);
    if (fs.heartbeat()) {
      shortest = std::min(shortest, fs.config().heartbeat_timeout);
      deadlines = true;
    }
    for (double s : fs.config().command_timeout) {
      if (s <= 0) continue;
      shortest = std::min(shortest, s);
      deadlines = true;
    }
    if (options_.kept_timed) {
      const std::string resumed = unit->keepTimedIn(*options_.kept_timed);
      if (!resumed.empty() && options_.info)
        options_.info(dc.name + ": the previous node's timed commands still run: " + resumed);
    }
    by_address_[unit->address()] = unit.get();
    units_.push_back(std::move(unit));
  }
  // Deadlines are checked at a tenth of the shortest timeout: a trigger fires at most 10 % late.
  if (deadlines) check_period_ = std::max(0.005, shortest / 10);
  bus_safe_time_ = busSafeTime();  // after the reply delays and the check period
  if (config_.share.enabled) {
    // The answer bound needs the link's worst transaction, and a thread that answers at the
    // bound: none on a stepped bus (the simulation's steps run alone, deterministic).
    ShareGateway::TransactionTime transaction_time;
    if (Link* link = options_.link; link && !options_.stepped)
      transaction_time = [link](const Request& r) { return link->worstTransactionSeconds(r); };
    share_ = std::make_unique<ShareGateway>(
        *scheduler_, config_.share, [this](uint8_t slave) { return deviceAt(slave); },
        std::move(transaction_time), clock_);
    share_->onWriteDone([this](const Request& r, const Result& done) {
      externalWrite(r, done, CommandSource::kShare);
    });
  }
}

BusRuntime::~BusRuntime() {
  for (auto& u : units_) u->stopKeeping();  // a killed node keeps nothing more
  // The bus's queued jobs and the share's answers call into the units: they end first.
  if (share_) share_->stop();
  scheduler_->stop();
}

DeviceUnit* BusRuntime::unit(const std::string& name) {
  for (auto& u : units_)
    if (u->name() == name) return u.get();
  return nullptr;
}

std::string BusRuntime::deviceAt(uint8_t slave) const {
  const auto it = by_address_.find(slave);
  return it == by_address_.end() ? std::string() : it->second->name();
}

// ---- the trigger clock ------------------------------------------------------------------------

void BusRuntime::feedHeartbeat() {
  if (bus_heartbeat_) bus_heartbeat_->feed();
}

void BusRuntime::feedDeviceHeartbeat(const std::string& device) {
  DeviceUnit* u = unit(device);
  if (u && u->failsafe().heartbeat()) u->failsafe().heartbeat()->feed();
}

// Devices that answer first: the bus runs the safe writes in the order they are queued, and a
// silent device's would hold the others' back by response_timeout x (retries + 1) per frame.
std::vector<DeviceUnit*> BusRuntime::answeringFirst() const {
  std::vector<DeviceUnit*> order;
  order.reserve(units_.size());
  for (const auto& u : units_) order.push_back(u.get());
  std::stable_sort(order.begin(), order.end(), [this](DeviceUnit* x, DeviceUnit* y) {
    return scheduler_->health(x->name()).consecutive_failures == 0 &&
           scheduler_->health(y->name()).consecutive_failures > 0;
  });
  return order;
}

void BusRuntime::checkDeadlines() {
  const std::vector<DeviceUnit*> order = answeringFirst();
  if (bus_heartbeat_ && bus_heartbeat_->expired()) {
    const std::string reason = "no message on " + config_.heartbeat_topic + " within " +
                               numberText(config_.heartbeat_timeout) + " s";
    for (DeviceUnit* u : order) u->applySafe(Trigger::kHeartbeat, reason);
  }
  for (DeviceUnit* u : order) u->checkDeadlines();
}

// docs/failsafe.md, "How long until safe". The transactions are those of the largest frames the
// node writes or reads for outputs and signals (8 registers: 25 bytes out, 21 back).
std::optional<SafeTime> BusRuntime::safeTime(const DeviceUnit& unit, size_t writes_ahead) const {
  if (!unit.hasSafeStates()) return std::nullopt;
  const FailsafeConfig& fs = unit.failsafe().config();
  double timeout = 0;
  if (bus_heartbeat_) timeout = std::max(timeout, config_.heartbeat_timeout);
  if (!fs.heartbeat_topic.empty()) timeout = std::max(timeout, fs.heartbeat_timeout);
  for (double s : fs.command_timeout) timeout = std::max(timeout, s);
  if (timeout <= 0) return std::nullopt;
  SafeTime t = safeAfterTrigger(writes_ahead);
  t.trigger_timeout = timeout;
  return t;
}

SafeTime BusRuntime::safeAfterTrigger(size_t writes_ahead) const {
  SafeTime t = bus_safe_time_;
  t.writes_ahead = writes_ahead;
  return t;
}

// The configuration's part of every safe time, once: the simulation asks for it after every step.
SafeTime BusRuntime::busSafeTime() const {
  SafeTime t;
  t.check_period = check_period_;
  t.devices = units_.size();
  const double character = characterTime(config_.link);
  // Through a gateway each answer also takes the network's time.
  const bool networked = config_.link_target.type && config_.link_target.type->networked;
  const double network = networked ? config_.link.network_allowance : 0.0;
  constexpr size_t kRequestBytes = 25, kReplyBytes = 21, kRegisters = 8;
  for (const auto& u : units_) {
    const uint8_t slave = u->address();
    const double worst =
        options_.link
            ? std::max(options_.link->worstTransactionSeconds(Request::writeMultipleRegisters(
                           slave, 0, std::vector<uint16_t>(kRegisters))),
                       options_.link->worstTransactionSeconds(
                           Request::readHoldingRegisters(slave, 0, kRegisters)))
            : (1 + std::max(0, config_.link.retries)) *
                  (effectiveResponseTimeout(config_.link, kRequestBytes) +
                   static_cast<double>(kRequestBytes + kReplyBytes) * character +
                   effectiveByteTimeout(config_.link) + u->device().config().reply_delay);
    t.worst_transaction = std::max(t.worst_transaction, worst);
    t.answered_transaction =
        std::max(t.answered_transaction,
                 static_cast<double>(kRequestBytes + kReplyBytes) * character +
                     2 * frameGap(config_.link) + u->device().config().reply_delay + network);
  }
  return t;
}

// ---- start and stop ---------------------------------------------------------------------------

BusRuntime::Pending BusRuntime::applySafeEverywhere(Trigger trigger, const std::string& reason,
                                                    bool only_on_start) {
  Pending pending;
  for (DeviceUnit* u : answeringFirst())
    if (only_on_start ? u->safeOnStart() : u->hasSafeStates())
      pending.emplace_back(u->name(), u->applySafe(trigger, reason));
  return pending;
}

bool BusRuntime::allDone(const Pending& writes) {
  return std::all_of(writes.begin(), writes.end(), [](const auto& w) { return isReady(w.second); });
}

bool BusRuntime::allDone(const Outcomes& outcomes) {
  return std::all_of(outcomes.begin(), outcomes.end(),
                     [](const WriteOutcome& o) { return o.result.has_value(); });
}

BusRuntime::Outcomes BusRuntime::outcomesOf(Pending& writes) {
  Outcomes out;
  out.reserve(writes.size());
  for (auto& [device, done] : writes) {
    WriteOutcome o{device, std::nullopt};
    if (done.valid() && isReady(done)) o.result = done.get();
    out.push_back(std::move(o));
  }
  return out;
}

// on_start: safe puts those outputs there before any command is taken, and before the first
// poll, so that a restart is never seen in them. All are queued at once and awaited together.
BusRuntime::Outcomes BusRuntime::start(const AwaitWrites& await,
                                       const std::function<void()>& before_commands) {
  const Clock::time_point began = clock_.now();
  if (options_.stepped)
    scheduler_->startStepping();
  else
    scheduler_->start();
  Pending writes = applySafeEverywhere(Trigger::kStart, "on_start: safe", true);
  await(writes, began + seconds(config_.shutdown_timeout + kStartWriteGrace));
  Outcomes outcomes = outcomesOf(writes);
  if (before_commands) before_commands();
  // The heartbeats count from here: no message could be taken while the start writes ran, so a
  // live controller is not taken as lost at start.
  feedHeartbeat();
  for (auto& u : units_)
    if (Watchdog* w = u->failsafe().heartbeat()) w->feed();
  for (auto& u : units_) u->addPolls();
  started_ = true;
  return outcomes;
}

// No client's request after the safe states (a client's write run after them would undo
// them), then the safe writes.
BusRuntime::Outcomes BusRuntime::stop(const AwaitWrites& await) {
  stop_deadline_ = clock_.now() + seconds(config_.shutdown_timeout);
  started_ = false;
  if (share_) share_->stop();
  Pending writes = applySafeEverywhere(Trigger::kShutdown, "node stops", false);
  await(writes, stop_deadline_);
  return outcomesOf(writes);
}

bool BusRuntime::stopBus(Clock::duration grace) {
  return scheduler_->stopBy(stop_deadline_ + grace);
}

// ---- what the node carries for others --------------------------------------------------------

std::string BusRuntime::rawWriteRefusal(uint8_t slave) const {
  if (!config_.allow_raw_writes)
    return "raw writes are off: set allow_raw_writes: true in the bus configuration to use them "
           "(they can change any device setting)";
  if (slave == kBroadcastAddress)
    return "slave: 0 (broadcast) is outside 1-255: a broadcast is never confirmed";
  return {};
}

std::future<Result> BusRuntime::rawWrite(const Request& request, DeviceUnit::Call call) {
  const std::string refused = rawWriteRefusal(request.slave);
  if (!refused.empty()) return readyResult(Result::failure(ErrorKind::kInvalidArgument, refused));
  const std::string problem = request.validate();
  if (!problem.empty()) return readyResult(Result::failure(ErrorKind::kInvalidArgument, problem));
  const std::string known = deviceAt(request.slave);
  const std::string owner = known.empty() ? "slave " + std::to_string(request.slave) : known;
  return scheduler_->submit(
      owner,
      [this, sent = forwarded(request), done = std::move(call.done)](Transport& t) {
        // Sent once: a raw write may start something (an LC flash through FC16).
        Result r = t.execute(sent);
        externalWrite(sent, r, CommandSource::kRaw);
        if (done) done(r);
        return r;
      },
      call.tag);
}

void BusRuntime::externalWrite(const Request& request, const Result& result, CommandSource source) {
  if (request.slave != kBroadcastAddress) {
    const auto it = by_address_.find(request.slave);
    if (it != by_address_.end()) it->second->externalWrite(request, result, source);
    return;
  }
  for (auto& u : units_) u->externalWrite(request, result, source);
}

}  // namespace modbus_rtu_driver
