#include "modbus_rtu_driver/simulation/sim_node.h"

#include <algorithm>
#include <chrono>
#include <utility>

#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/devices/generic_device.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/devices/registry.h"
#include "modbus_rtu_driver/devices/yespeed_pdu.h"

namespace modbus_rtu_driver {

namespace {

bool isReady(const std::future<Result>& f) {
  return !f.valid() || f.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
}

}  // namespace

SimNode::SimNode(SimNodeOptions options, Transport& transport, Clock& clock, SimNodeHooks hooks)
    : options_(std::move(options)), clock_(clock), hooks_(std::move(hooks)) {
  scheduler_ = std::make_unique<BusScheduler>(transport, options_.scheduling, clock_);
  double shortest = 0.5;
  bool deadlines = false;
  if (options_.heartbeat_timeout > 0) {
    heartbeat_ = std::make_unique<Watchdog>(options_.heartbeat_timeout, clock_);
    shortest = std::min(shortest, options_.heartbeat_timeout);
    deadlines = true;
  }
  for (const DeviceConfig& dc : options_.devices) {
    auto e = std::make_unique<Entry>();
    e->device = createDevice(dc);  // the registered class of its type, as BusNode builds it
    scheduler_->addDevice(dc.name);
    if (e->device->outputCount() > 0) {
      e->failsafe = std::make_unique<DeviceFailsafe>(*e->device, *scheduler_, clock_);
      e->failsafe->setBusHeartbeat(heartbeat_.get(), "/alive");
      e->failsafe->setReportSink([this](const FailsafeReport& r) {
        if (hooks_.report) hooks_.report(r);
      });
      // DeviceAdapter's commands: the same job bodies, queued with the operation they run for.
      const std::string name = dc.name;
      e->commands = std::make_unique<DeviceCommands>(
          *e->device, *e->failsafe, [this, name](BusScheduler::Job job) {
            return runOp(submitting_op_, name, std::exchange(submitting_done_, {}), std::move(job));
          });
      e->commands->setWritten(
          [this, name](const std::vector<uint8_t>& channels, const std::vector<bool>& states) {
            if (hooks_.written) hooks_.written(name, channels, states);
          });
      keepTimed(*e);
      // BusNode::startFailsafe watches a device's own heartbeat too.
      if (e->failsafe->heartbeat()) {
        shortest = std::min(shortest, dc.failsafe.heartbeat_timeout);
        deadlines = true;
      }
      for (double s : dc.failsafe.command_timeout) {
        if (s <= 0) continue;
        shortest = std::min(shortest, s);
        deadlines = true;
      }
    }
    if (!e->failsafe) {
      // GenericAdapter's fail-safe: the signals' safe values.
      e->generic_safe =
          std::make_unique<GenericFailsafe>(static_cast<GenericDevice&>(*e->device), *scheduler_);
      e->generic_safe->setReportSink([this](const FailsafeReport& r) {
        if (hooks_.report) hooks_.report(r);
      });
    }
    entries_.push_back(std::move(e));
  }
  // BusNode::startFailsafe: deadlines at a tenth of the shortest timeout.
  if (deadlines) check_period_ = std::max(0.005, shortest / 10);
}

void SimNode::keepTimed(Entry& e) {
  // DeviceAdapter::keepTimedIn: the previous node's timed commands resumed before the first
  // poll, this node's kept while they run, also as the stop's safe writes end them (the real
  // node flushes those after its bus thread ended: RunningTimedParameter).
  if (!options_.kept_timed) return;
  const std::string name = e.device->name();
  auto* kept = options_.kept_timed;
  auto seconds = [this] {
    return std::chrono::duration<double>(clock_.now().time_since_epoch()).count();
  };
  const auto it = kept->find(name);
  if (it != kept->end()) {
    const std::vector<TimedIntent> running =
        resumeTimedCommands(it->second, seconds(), e.device->outputCount());
    if (!running.empty()) e.failsafe->resumeTimed(running);
  }
  e.failsafe->setTimedChanged([this, kept, name, seconds](const std::vector<TimedIntent>& running) {
    if (killed_) return;
    std::vector<KeptTimedCommand> list = keepTimedCommands(running, seconds());
    if (list.empty())
      kept->erase(name);  // as RunningTimedParameter deletes the key
    else
      (*kept)[name] = std::move(list);
  });
}

SimNode::~SimNode() {
  killed_ = true;  // a killed node keeps nothing more
  // The bus's queued jobs call into the fail-safes: they fail unsent before those go.
  scheduler_->stop();
}

SimNode::Entry* SimNode::entry(const std::string& name) {
  for (auto& e : entries_)
    if (e->device->name() == name) return e.get();
  return nullptr;
}

Device* SimNode::device(const std::string& name) {
  Entry* e = entry(name);
  return e ? e->device.get() : nullptr;
}

DeviceFailsafe* SimNode::failsafe(const std::string& name) {
  Entry* e = entry(name);
  return e ? e->failsafe.get() : nullptr;
}

std::vector<SimNode::Entry*> SimNode::answeringFirst() {
  std::vector<Entry*> order;
  order.reserve(entries_.size());
  for (auto& e : entries_) order.push_back(e.get());
  std::stable_sort(order.begin(), order.end(), [this](Entry* x, Entry* y) {
    return scheduler_->health(x->device->name()).consecutive_failures == 0 &&
           scheduler_->health(y->device->name()).consecutive_failures > 0;
  });
  return order;
}

std::future<Result> SimNode::applySafe(Entry& e, const std::string& trigger,
                                       const std::string& reason) {
  if (e.failsafe) return e.failsafe->applySafe(trigger, reason);
  return e.generic_safe->applySafe(trigger, reason);
}

void SimNode::beginStart() {
  scheduler_->startStepping();
  for (auto& e : entries_)
    if (e->device->config().failsafe.on_start_safe)
      start_writes_.push_back(applySafe(*e, "start", "on_start: safe"));
}

bool SimNode::startWritesDone() const {
  return std::all_of(start_writes_.begin(), start_writes_.end(), isReady);
}

void SimNode::finishStart() {
  start_writes_.clear();
  // The heartbeats count from here (BusNode::start).
  if (heartbeat_) heartbeat_->feed();
  for (auto& e : entries_)
    if (e->failsafe && e->failsafe->heartbeat()) e->failsafe->heartbeat()->feed();
  for (auto& up : entries_) {
    Entry* e = up.get();
    auto device = e->device;
    if (e->failsafe) {
      scheduler_->addPoll(
          device->name(), device->config().poll_rate,
          [this, e](Transport& t) {
            if (hooks_.poll_starting) hooks_.poll_starting(e->device->name());
            e->failsafe->pollStarting();
            return e->device->poll(t);
          },
          [this, e](const Result& r) {
            if (r.ok()) e->failsafe->afterPoll();
            if (hooks_.polled) hooks_.polled(e->device->name(), r);
          });
    } else {
      auto& generic = static_cast<GenericDevice&>(*device);
      for (size_t g = 0; g < generic.groups().size(); ++g) {
        if (generic.groups()[g].signals.empty()) continue;
        scheduler_->addPoll(
            device->name(), generic.groups()[g].rate,
            [this, e, g](Transport& t) {
              if (hooks_.poll_starting) hooks_.poll_starting(e->device->name());
              return static_cast<GenericDevice&>(*e->device).pollGroup(t, g);
            },
            [this, e](const Result& r) {
              e->generic_safe->afterPoll(r);  // GenericAdapter::onPoll
              if (hooks_.polled) hooks_.polled(e->device->name(), r);
            });
      }
    }
  }
  started_ = true;
}

void SimNode::beginStop() {
  share_closed_ = true;
  scheduler_->closeShared("the share stopped (the node is stopping)");
  started_ = false;
  for (Entry* e : answeringFirst()) {
    const bool safe = e->failsafe ? e->failsafe->hasSafeStates() : e->generic_safe->hasSafeValues();
    if (safe) stop_writes_.push_back(applySafe(*e, "shutdown", "node stops"));
  }
}

bool SimNode::stopWritesDone() const {
  return std::all_of(stop_writes_.begin(), stop_writes_.end(), isReady);
}

void SimNode::checkDeadlines() {
  const std::vector<Entry*> order = answeringFirst();
  if (heartbeat_ && heartbeat_->expired()) {
    const std::string reason =
        "no message on /alive within " + numberText(options_.heartbeat_timeout) + " s";
    for (Entry* e : order) applySafe(*e, "heartbeat", reason);
  }
  for (Entry* e : order)
    if (e->failsafe) e->failsafe->checkDeadlines();
}

void SimNode::feedHeartbeat() {
  if (heartbeat_) heartbeat_->feed();
}

void SimNode::feedDeviceHeartbeat(const std::string& device) {
  Entry* e = entry(device);
  if (e && e->failsafe && e->failsafe->heartbeat()) e->failsafe->heartbeat()->feed();
}

std::future<Result> SimNode::runOp(uint64_t op, const std::string& device, Done done,
                                   std::function<Result(Transport&)> job) {
  return scheduler_->submit(device,
                            [this, op, done = std::move(done), job = std::move(job)](Transport& t) {
                              const uint64_t outer = current_op_;
                              current_op_ = op;
                              Result r = job(t);
                              current_op_ = outer;
                              if (done) done(r);
                              return r;
                            });
}

std::future<Result> SimNode::viaCommands(uint64_t op, Done done,
                                         const std::function<std::future<Result>()>& call) {
  // DeviceCommands queues at most one job per call, through the Submit above, which takes these.
  submitting_op_ = op;
  submitting_done_ = std::move(done);
  std::future<Result> f = call();
  submitting_op_ = 0;
  submitting_done_ = {};  // not queued (refused, or merged into a queued job): not called
  return f;
}

std::future<Result> SimNode::set(uint64_t op, const std::string& device,
                                 const std::vector<uint8_t>& channels,
                                 const std::vector<bool>& states, Done done) {
  Entry* e = entry(device);
  return viaCommands(op, std::move(done), [&] { return e->commands->write(channels, states); });
}

std::future<Result> SimNode::command(uint64_t op, const std::string& device, uint8_t channel,
                                     bool state, Done done) {
  // DeviceAdapter::onCommand. The caller of a topic gets no answer: `done` (the model) learns how
  // the write that carried it went, also when it joined a queued job.
  Entry* e = entry(device);
  return viaCommands(op, {}, [&] { return e->commands->command(channel, state, std::move(done)); });
}

std::future<Result> SimNode::pulse(uint64_t op, const std::string& device, uint8_t channel,
                                   bool state, double duration, Done done) {
  // LcRelay8Adapter::onPulse (its read back publishes nothing here).
  Entry* e = entry(device);
  const std::string problem = LcRelay8::validatePulse(channel, duration);
  if (!problem.empty()) return readyResult(Result::failure(ErrorKind::kInvalidArgument, problem));
  auto& board = static_cast<LcRelay8&>(*e->device);
  return viaCommands(op, std::move(done), [&] {
    return e->commands->timed(
        TimedIntent{channel, state, !state, duration},
        [&board, channel, state, duration](Transport& t) {
          return board.pulse(t, channel, state, duration);
        },
        [&board](Transport& t) { board.poll(t); });
  });
}

std::future<Result> SimNode::setPwm(uint64_t op, const std::string& device, const PwmSettings& s,
                                    Done done) {
  // Ld58a08Adapter::onSetPwm.
  Entry* e = entry(device);
  const std::string problem = Ld58a08::validatePwm(s);
  if (!problem.empty()) return readyResult(Result::failure(ErrorKind::kInvalidArgument, problem));
  auto& board = static_cast<Ld58a08&>(*e->device);
  return viaCommands(op, std::move(done), [&] {
    return e->commands->timed(
        board.pwmIntent(s), [&board, s](Transport& t) { return board.setPwm(t, s); },
        [&board](Transport& t) { board.readPwm(t); });
  });
}

std::future<Result> SimNode::stopPwm(uint64_t op, const std::string& device, uint8_t channel,
                                     Done done) {
  // Ld58a08Adapter::onStopPwm.
  Entry* e = entry(device);
  auto& board = static_cast<Ld58a08&>(*e->device);
  return viaCommands(op, std::move(done), [&] {
    return e->commands->stopTimed(
        channel, [&board, channel](Transport& t) { return board.stopPwm(t, channel); },
        [&board](Transport& t) { board.readPwm(t); });
  });
}

size_t SimNode::queuedJobs() const {
  return scheduler_ ? scheduler_->queuedJobs() : 0;
}

void SimNode::externalWrite(const Request& request, const Result& result, CommandSource source) {
  // BusNode::externalWrite and DeviceAdapter::externalWrite.
  for (auto& e : entries_)
    if (e->failsafe &&
        (request.slave == kBroadcastAddress || e->device->address() == request.slave))
      e->failsafe->externalWrite(request, result, source);
}

std::future<Result> SimNode::share(uint64_t op, const Request& request, Done done) {
  // ShareGateway::handle (the TCP server aside): a client's write is sent once; confirmed, it
  // is the fail-safe's externalWrite before any later job runs.
  auto promise = std::make_shared<std::promise<Result>>();
  std::future<Result> f = promise->get_future();
  std::string device;
  for (auto& e : entries_)
    if (e->device->address() == request.slave) device = e->device->name();
  const Request sent = forwarded(request);
  scheduler_->submitShared(
      device,
      [this, op, sent, done = std::move(done)](Transport& t) {
        const uint64_t outer = current_op_;
        current_op_ = op;
        Result r = t.execute(sent);
        current_op_ = outer;
        if (!isReadFunction(sent.function)) externalWrite(sent, r, CommandSource::kShare);
        if (done) done(r);
        return r;
      },
      [promise](const Result& r) { promise->set_value(r); });
  return f;
}

std::future<Result> SimNode::raw(uint64_t op, const Request& request, Done done) {
  // RawWrites::run: the request as the service builds it, confirmed writes are externalWrite.
  const std::string problem = request.validate();
  if (!problem.empty()) return readyResult(Result::failure(ErrorKind::kInvalidArgument, problem));
  std::string owner = "slave " + std::to_string(request.slave);
  for (auto& e : entries_)
    if (e->device->address() == request.slave) owner = e->device->name();
  return runOp(op, owner, std::move(done), [this, sent = forwarded(request)](Transport& t) {
    Result r = t.execute(sent);
    externalWrite(sent, r, CommandSource::kRaw);
    return r;
  });
}

std::future<Result> SimNode::writeSignal(uint64_t op, const std::string& device, size_t signal,
                                         double value, Done done) {
  Entry* e = entry(device);
  auto& generic = static_cast<GenericDevice&>(*e->device);
  std::vector<uint16_t> words;
  const std::string problem = generic.encodeWrite(signal, value, &words);
  if (!problem.empty()) return readyResult(Result::failure(ErrorKind::kInvalidArgument, problem));
  GenericFailsafe& safe = *e->generic_safe;  // GenericAdapter::write
  return runOp(op, device, std::move(done),
               [&safe, signal, value](Transport& t) { return safe.write(t, signal, value); });
}

}  // namespace modbus_rtu_driver
