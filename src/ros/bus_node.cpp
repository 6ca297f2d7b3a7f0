#include "modbus_rtu_driver/ros/bus_node.h"

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <topic_tools/shape_shifter.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "modbus_rtu_driver/core/bus/realtime.h"
#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/core/link/make_link.h"
#include "modbus_rtu_driver/ros/adapter_registry.h"
#include "modbus_rtu_driver/ros/publish_shared.h"
#include "modbus_rtu_driver/ros/yaml_params.h"

namespace modbus_rtu_driver {

namespace {

// The node's wait for the start's and the stop's safe writes: the bus thread does them.
void awaitFutures(const BusRuntime::Pending& writes, Clock::time_point deadline) {
  for (const auto& write : writes)
    if (write.second.valid()) write.second.wait_until(deadline);
}

}  // namespace

BusNode::BusNode(const ros::NodeHandle& private_nh) : nh_(private_nh) {}

BusNode::~BusNode() {
  // The bus thread calls into the adapters and the share: the runtime (the share, then the bus)
  // stops before they go.
  runtime_.reset();
  if (publish_queue_) publish_queue_->stop();  // what the bus thread left to publish
}

// ~failsafe, the heartbeat subscriptions (any message type) and the deadline timer; the
// decisions are the runtime's.
void BusNode::startFailsafe() {
  failsafe_pub_ = nh_.advertise<FailsafeEvent>("failsafe", 10, true);
  ros::NodeHandle topics;  // heartbeat topics resolve in the node's namespace
  auto watch = [&](const std::string& topic, Watchdog* dog) {
    heartbeat_subs_.push_back(topics.subscribe<topic_tools::ShapeShifter>(
        topic, 1, [dog](const topic_tools::ShapeShifter::ConstPtr&) { dog->feed(); }));
  };
  if (Watchdog* dog = runtime_->busHeartbeat()) watch(config_.heartbeat_topic, dog);
  for (const auto& u : runtime_->units())
    if (Watchdog* dog = u->failsafe().heartbeat())
      watch(u->failsafe().config().heartbeat_topic, dog);
  for (auto& a : adapters_)
    a->setFailsafeSink([this](const FailsafeEvent& e) {
      postOrRun(rosPublishing(), [this, e] { publishShared(failsafe_pub_, e); });
    });
  if (runtime_->checkPeriod() <= 0) return;  // no heartbeat and no command timeout
  failsafe_timer_ =
      nh_.createSteadyTimer(ros::WallDuration(runtime_->checkPeriod()),
                            [this](const ros::SteadyTimerEvent&) { runtime_->checkDeadlines(); });
}

void BusNode::shutdown() {
  if (!runtime_) return;
  failsafe_timer_.stop();
  // The runtime closes the share (no client request after the safe states, queued ones
  // refused) and queues the safe writes, devices that answer first. Bounded: a device that
  // cannot be reached is logged and the node exits anyway. The whole stop fits in roslaunch's
  // 15 s between SIGINT and SIGTERM (SIGKILL 2 s later): shutdown_timeout is at most
  // kMaxShutdownTimeout, and the bus thread, which first finishes the transaction it is in,
  // gets kBusStopGrace more.
  const auto start = std::chrono::steady_clock::now();
  for (const auto& [name, result] : runtime_->stop(awaitFutures)) {
    // rosconsole has shut down with ROS: stderr is what the user sees now.
    if (!result)
      std::fprintf(stderr,
                   "[ERROR] %s: safe states not confirmed within shutdown_timeout (%.1f s); "
                   "exiting anyway\n",
                   name.c_str(), config_.shutdown_timeout);
    else if (!result->ok())
      std::fprintf(stderr, "[ERROR] %s: safe states not reached before exit: %s\n", name.c_str(),
                   result->message.c_str());
  }
  if (!runtime_->stopBus(kBusStopGrace)) {
    // Still in one transaction (a silent device with long timeouts): waiting on would run into
    // roslaunch's SIGKILL. The port is closed by the kernel as the process ends.
    std::fprintf(stderr,
                 "[ERROR] the bus thread is still in a transaction %.1f s after the stop began; "
                 "exiting without waiting for it\n",
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    std::fflush(nullptr);
    std::_Exit(0);
  }
  // The bus thread has ended: the timed commands the safe writes ended are gone from the lists
  // kept for the next node. After ROS's shutdown roscpp tries the master once: a master that is
  // gone costs no wait, one that does not answer at most kParameterGrace.
  if (running_timed_ && !running_timed_->flush(std::chrono::steady_clock::now() + kParameterGrace))
    std::fprintf(stderr,
                 "[ERROR] %s not updated within %.0f s (the master does not answer): "
                 "a node started under this roscore may resume timed commands the stop ended\n",
                 RunningTimedParameter::namespaceOf(nh_.getNamespace()).c_str(),
                 std::chrono::duration<double>(kParameterGrace).count());
  if (publish_queue_) publish_queue_->stop();
}

bool BusNode::start() {
  XmlRpc::XmlRpcValue params;
  if (!nh_.getParam("", params) || params.getType() != XmlRpc::XmlRpcValue::TypeStruct) {
    ROS_FATAL("no configuration in %s: load a YAML file with rosparam (see config/)",
              nh_.getNamespace().c_str());
    return false;
  }
  std::string error;
  YAML::Node root = toYaml(params);
  // Not configuration: where releases before 2026-12 kept the running timed commands for the
  // next node (now RunningTimedParameter::namespaceOf, outside the node's namespace); a node
  // upgraded under a running roscore may still find it.
  root.remove("running_timed");
  if (!parseBusConfig(root, &config_, &error)) {
    ROS_FATAL("invalid configuration in %s: %s", nh_.getNamespace().c_str(), error.c_str());
    return false;
  }
  for (const std::string& word : config_.deprecated)
    ROS_WARN("%s: %s; removed in the next release", nh_.getNamespace().c_str(), word.c_str());
  link_ = makeLink(config_.link, config_.link_target);
  // Only what needs it starts the publishing thread (see rosPublishing()).
  if (!config_.wire_log.empty() || config_.realtime_priority > 0)
    publish_queue_ = std::make_unique<TaskQueue>();
  if (!config_.wire_log.empty() && !openWireLog(&error)) {
    ROS_FATAL("wire_log: %s", error.c_str());
    return false;
  }
  // A share that cannot listen stops the node before the bus is touched (no on_start write).
  if (config_.share.enabled && !ShareBridge::canStart(config_.share, &error)) {
    ROS_FATAL("%s", error.c_str());
    return false;
  }
  running_timed_ = RunningTimedParameter::onParameterServer(nh_);
  BusRuntime::Options options;
  options.scheduling = schedulingOptions();
  options.link = link_.get();
  options.kept_timed = running_timed_.get();
  options.info = [](const std::string& line) { ROS_INFO("%s", line.c_str()); };
  runtime_ = std::make_unique<BusRuntime>(config_, *link_, std::move(options));
  for (const auto& unit : runtime_->units()) {
    auto adapter = createAdapter(*unit, runtime_->scheduler(), nh_);
    if (!adapter) {
      ROS_FATAL("devices/%s/type: '%s' has no ROS interface", unit->name().c_str(),
                unit->device().type());
      return false;
    }
    adapters_.push_back(std::move(adapter));
  }
  raw_writes_ = std::make_unique<RawWrites>(nh_, *runtime_);
  stateSafeTimes();

  diagnostics_ = std::make_unique<diagnostic_updater::Updater>();
  diagnostics_->setHardwareID(config_.link.port);
  diagnostics_->add("bus " + config_.link.port, this, &BusNode::diagnoseBus);
  for (auto& a : adapters_) {
    DeviceAdapter* raw = a.get();
    diagnostics_->add("device " + a->name(),
                      [raw](diagnostic_updater::DiagnosticStatusWrapper& s) { raw->diagnose(s); });
  }
  diagnostics_timer_ =
      nh_.createTimer(ros::Duration(config_.diagnostic_period),
                      [this](const ros::TimerEvent&) { diagnostics_->force_update(); });

  startFailsafe();
  // on_start: safe puts those outputs there before any command is taken (and before the first
  // poll, so a restart is never seen in them). The topics' publishers are ready before the polls
  // start; the heartbeats count from the end of start() (no message could arrive while it
  // blocked on those writes: the spinner runs after it).
  const auto outcomes = runtime_->start(awaitFutures, [this] {
    for (auto& a : adapters_) {
      a->setPublishPolicy({config_.publish_on_change, config_.keep_alive});
      a->setPublishQueue(rosPublishing());
      a->start();
    }
  });
  for (const auto& [name, result] : outcomes)
    if (!result) ROS_ERROR("%s: start-up safe states not confirmed in time", name.c_str());
  if (ShareGateway* gateway = runtime_->share()) {
    share_ = std::make_unique<ShareBridge>(*gateway, config_.share);
    if (!share_->start(&error)) {
      ROS_FATAL("%s", error.c_str());  // names the share's key
      return false;
    }
    diagnostics_->add("share", share_.get(), &ShareBridge::diagnose);
    ROS_INFO("share: Modbus TCP on %s:%u (%s)", config_.share.server.host.c_str(),
             static_cast<unsigned>(config_.share.server.port),
             config_.share.read_only ? "read only" : "reads and writes");
    ROS_INFO(
        "share: every request answered within %.3f s (%s; one that cannot start in time gets "
        "exception 0B, unsent): give clients a timeout of at least that",
        share_->answerBound(),
        config_.share.answer_within > 0 ? "share/answer_within" : "twice the longest transaction");
  }
  ROS_INFO("bus %s (%s) at %d baud, %s parity: %zu device(s)", config_.link.port.c_str(),
           link_->target().type->name, config_.link.baud, parityName(config_.link.parity),
           adapters_.size());
  return true;
}

// docs/failsafe.md, "How long until safe": ahead of a safe write, at most one write per service
// thread (a service call waits for its write) and one command job per device with outputs.
void BusNode::stateSafeTimes() {
  size_t writes_ahead = kServiceThreads;
  for (const auto& u : runtime_->units())
    if (u->device().outputCount() > 0) ++writes_ahead;
  for (size_t i = 0; i < adapters_.size(); ++i) {
    const DeviceUnit& unit = *runtime_->units()[i];
    const std::optional<SafeTime> t = runtime_->safeTime(unit, writes_ahead);
    if (!t) continue;
    adapters_[i]->setSafeTime(*t);
    ROS_INFO(
        "%s: safe within %.3f s of its last heartbeat or command (timeout %.3f s, deadline check "
        "%.3f s, %.3f s after it: %zu write(s) ahead, %zu device(s))",
        unit.name().c_str(), t->total(), t->trigger_timeout, t->check_period, t->afterTrigger(),
        t->writes_ahead, t->devices);
  }
}

// The bus thread copies each frame and its times; the publishing thread formats and writes it
// (line-buffered, so `tail -f` shows it as it happens).
bool BusNode::openWireLog(std::string* error) {
  wire_log_.reset(std::fopen(config_.wire_log.c_str(), "w"));
  if (!wire_log_) {
    *error = "cannot write " + config_.wire_log + ": " + std::strerror(errno);
    return false;
  }
  std::setvbuf(wire_log_.get(), nullptr, _IOLBF, 0);
  link_->setWireObserver([this](const WireEvent& e) {
    publish_queue_->post(
        [this, e] { std::fprintf(wire_log_.get(), "%s\n", formatWireEvent(e).c_str()); });
  });
  return true;
}

// A real-time bus thread hands its publishing to the publishing thread: roscpp's locks are
// shared with normal-priority threads (a priority inversion), and a subscriber's socket write
// has no place on it. At the normal priority it publishes itself: a thread hop per poll costs
// more CPU than publishing does (bench/results.md).
TaskQueue* BusNode::rosPublishing() const {
  return config_.realtime_priority > 0 ? publish_queue_.get() : nullptr;
}

BusScheduler::Options BusNode::schedulingOptions() {
  std::string error;
  if (config_.lock_memory) {
    memory_status_ = lockMemory(&error) ? "locked (mlockall)" : error;
    if (!error.empty()) ROS_WARN("lock_memory: %s", error.c_str());
  }
  BusScheduler::Options options;
  const int priority = config_.realtime_priority;
  if (priority > 0)
    options.on_thread_start = [this, priority] {
      std::string refused;
      const bool granted = raiseToRealtime(priority, &refused);
      if (!granted) ROS_WARN("realtime_priority: %s", refused.c_str());
      std::lock_guard<std::mutex> lock(realtime_mutex_);
      realtime_status_ = granted ? "SCHED_FIFO " + std::to_string(priority) : refused;
    };
  return options;
}

// Line errors (silence, garbled or misaddressed replies, i/o) in the last kErrorWindowSeconds:
// the level says how the bus is now; the totals stay in the values.
uint64_t BusNode::recentLineErrors(const LinkStats& s) {
  const uint64_t total = s.timeouts + s.crc_errors + s.wrong_address + s.malformed + s.io_errors;
  const ros::WallTime now = ros::WallTime::now();
  error_totals_.emplace_back(now, total);
  while (error_totals_.size() > 1 &&
         (now - error_totals_[1].first).toSec() >= static_cast<double>(kErrorWindowSeconds))
    error_totals_.pop_front();
  return total - error_totals_.front().second;
}

void BusNode::diagnoseBus(diagnostic_updater::DiagnosticStatusWrapper& status) {
  using diagnostic_msgs::DiagnosticStatus;
  const LinkStats s = link_->stats();
  const uint64_t recent = recentLineErrors(s);
  logRecoveries();
  if (!runtime_->scheduler().connected()) {
    status.summary(DiagnosticStatus::ERROR,
                   "port not open: " + runtime_->scheduler().connectionError());
    // A wrong port or a second node on it must show in the log, not only in /diagnostics.
    ROS_ERROR_THROTTLE(10.0, "bus %s: port not open: %s (retrying with backoff)",
                       config_.link.port.c_str(), runtime_->scheduler().connectionError().c_str());
  } else if (logged_all_silent_) {
    status.summary(DiagnosticStatus::ERROR, silentBusAdvice());
  } else if (recent > 0) {
    status.summary(DiagnosticStatus::WARN, "link up, " + std::to_string(recent) +
                                               " failed attempt(s) in the last " +
                                               std::to_string(kErrorWindowSeconds) + " s");
  } else {
    status.summary(DiagnosticStatus::OK, "link up");
  }
  status.add("port", config_.link.port);
  status.add("transport", link_->target().type->name);
  status.add("baud", config_.link.baud);
  status.add("parity", parityName(config_.link.parity));
  // Whether the adapter took ASYNC_LOW_LATENCY: without it an FTDI adapter holds replies up to
  // its latency timer (16 ms by default).
  if (!link_->target().type->networked)
    status.add("low latency",
               link_->lowLatency() ? "yes" : "no (the adapter refused it or it is off)");
  else
    status.add("network allowance [s]", config_.link.network_allowance);
  {
    std::lock_guard<std::mutex> lock(realtime_mutex_);
    status.add("bus thread scheduling", realtime_status_);
    status.add("memory", memory_status_);
  }
  // What the bus thread hands to the publishing thread (wire_log; with realtime_priority its
  // ROS publishing too): a high-water mark near the capacity, or drops, mean it cannot keep up.
  if (publish_queue_) {
    status.add("publish queue high-water mark", publish_queue_->highWater());
    status.add("publish queue dropped", publish_queue_->dropped());
  }
  status.add("requests", s.requests);
  status.add("attempts", s.attempts);
  status.add("failed", s.failed);
  status.add("ok", s.ok);
  status.add("broadcasts", s.broadcasts);
  status.add("timeouts", s.timeouts);
  status.add("crc errors", s.crc_errors);
  status.add("wrong address", s.wrong_address);
  status.add("exceptions", s.exceptions);
  status.add("malformed", s.malformed);
  status.add("i/o errors", s.io_errors);
  status.add("retries", s.retries);
  status.add("reconnects", s.reconnects);
  status.add("stale bytes", s.stale_bytes);
  status.add("latency last [ms]", s.last_latency * 1e3);
  status.add("latency mean [ms]", s.mean_latency * 1e3);
  status.add("latency max [ms]", s.max_latency * 1e3);
}

std::string BusNode::silentBusAdvice() const {
  return "no device answers: check baud (" + std::to_string(config_.link.baud) + "), parity (" +
         parityName(config_.link.parity) + ") and wiring (A/B swapped, termination, ground)";
}

// Recoveries are logged as they are seen (diagnostics thread), so a bus that heals itself
// still leaves a trace; and a bus where nobody answers says what to check, once.
void BusNode::logRecoveries() {
  const PortReopens reopens = runtime_->scheduler().portReopens();
  if (reopens.count != logged_reopens_) {
    logged_reopens_ = reopens.count;
    ROS_INFO("bus %s: port open again after %s", config_.link.port.c_str(),
             secondsText(reopens.last_outage_seconds).c_str());
  }
  const BusScheduler& bus = runtime_->scheduler();
  const bool all_silent = !adapters_.empty() && bus.connected() &&
                          std::all_of(adapters_.begin(), adapters_.end(), [&bus](const auto& a) {
                            return !bus.health(a->name()).online;
                          });
  if (all_silent && !logged_all_silent_)
    ROS_WARN("bus %s: %s", config_.link.port.c_str(), silentBusAdvice().c_str());
  logged_all_silent_ = all_silent;
}

}  // namespace modbus_rtu_driver
