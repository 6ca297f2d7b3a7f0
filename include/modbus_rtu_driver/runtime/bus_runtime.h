// One bus, composed: the composition root of everything the node runs for a bus, ROS-free. It
// owns, and is the only place that wires:
//   - the scheduler (the bus thread) on the given transport, and one DeviceUnit per device
//     (the device, its fail-safe, its commands; a generic device's safe values in the same shape);
//   - the trigger clock: the bus heartbeat, each device's own heartbeat and command deadlines,
//     and the deadline check's period;
//   - the start sequence (on_start safe writes, then the heartbeats armed, then the polls) and
//     the stop sequence (the share closed first, then the safe writes, devices that answered
//     first, then the bus);
//   - the one address map: external writes (the share's, raw writes) reach the device they name;
//   - the share (Modbus TCP clients), when configured;
//   - the running timed commands kept for the next node, through a KeptTimedStore.
// The ROS node (ros/bus_node.h) turns messages into its calls and its state into topics and
// /diagnostics; the fail-safe's simulation runs this same object on a manual clock and an
// in-memory line (docs/architecture.md).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/core/bus/watchdog.h"
#include "modbus_rtu_driver/core/link/link.h"
#include "modbus_rtu_driver/core/server/share_gateway.h"
#include "modbus_rtu_driver/node_config/bus_config.h"
#include "modbus_rtu_driver/runtime/device_unit.h"
#include "modbus_rtu_driver/runtime/kept_timed_store.h"

namespace modbus_rtu_driver {

// How long a device's outputs can take to reach their safe state after a trigger
// (docs/failsafe.md, "How long until safe"): its parts, from the configuration.
struct SafeTime {
  double trigger_timeout = 0;       // s, the longest of the device's triggers' timeouts
  double check_period = 0;          // s, between deadline checks
  double worst_transaction = 0;     // s, one transaction nobody answers, every retry
  double answered_transaction = 0;  // s, one transaction answered (its frames and reply delay)
  size_t writes_ahead = 0;          // writes that may be queued before the safe write
  size_t devices = 0;               // every device's safe writes may go first
  // s from the trigger's deadline to the confirmed safe state: the check, the transaction on
  // the line and one per write ahead (each may find a silent device), and up to 6 answered
  // transactions per device and write ahead (a write, its read back, an LD58A08's PWM reads).
  double afterTrigger() const {
    return check_period + static_cast<double>(1 + writes_ahead) * worst_transaction +
           static_cast<double>(devices + writes_ahead) * 6 * answered_transaction;
  }
  // s from the last heartbeat (or command) to the confirmed safe state.
  double total() const { return trigger_timeout + afterTrigger(); }
};

class BusRuntime {
 public:
  struct Options {
    Clock* clock = &Clock::steady();  // what timeouts and deadlines are measured on
    // The simulation runs the bus itself (BusScheduler::step) instead of the bus thread.
    bool stepped = false;
    BusScheduler::Options scheduling;
    // The link under `transport` (the serial port, a gateway): devices' reply delays are set on
    // it, the safe time and the share's answer bound (not on a stepped bus) are computed from
    // its worst transaction. None: from the configuration alone; the share has no bound.
    Link* link = nullptr;
    // Where running timed commands are kept for the next node; none: nothing is kept.
    KeptTimedStore* kept_timed = nullptr;
    // Log lines of the runtime's own (what the previous node left running).
    std::function<void(const std::string&)> info;
  };
  using Pending = std::vector<std::pair<std::string, std::future<Result>>>;

  // `config` was checked by parseBusConfig; `transport` outlives the runtime.
  BusRuntime(BusConfig config, Transport& transport, Options options);
  // Without stop(): a killed node. Queued jobs fail unsent; nothing more is kept.
  ~BusRuntime();
  BusRuntime(const BusRuntime&) = delete;
  BusRuntime& operator=(const BusRuntime&) = delete;

  const BusConfig& config() const { return config_; }
  BusScheduler& scheduler() { return *scheduler_; }
  const std::vector<std::unique_ptr<DeviceUnit>>& units() const { return units_; }
  DeviceUnit* unit(const std::string& name);
  // The address map: the configured device at `slave`, or "" (none, or 0: every device).
  std::string deviceAt(uint8_t slave) const;
  // The share, when `share` is configured (nullptr otherwise).
  ShareGateway* share() { return share_.get(); }

  // ---- the trigger clock ----
  // A message on the bus heartbeat's topic, and on `device`'s own.
  void feedHeartbeat();
  void feedDeviceHeartbeat(const std::string& device);
  Watchdog* busHeartbeat() { return bus_heartbeat_.get(); }
  bool heartbeatLost() const { return bus_heartbeat_ && bus_heartbeat_->tripped(); }
  // s between deadline checks (a tenth of the shortest timeout, 5-500 ms); 0: nothing to check.
  double checkPeriod() const { return check_period_; }
  // Heartbeats lost and command deadlines passed: their safe writes, devices that answer first.
  void checkDeadlines();
  // How long `unit`'s outputs take to reach their safe state after a trigger, with
  // `writes_ahead` writes queued before its safe write; none when it has no trigger (no
  // heartbeat, no command timeout) or no safe state.
  std::optional<SafeTime> safeTime(const DeviceUnit& unit, size_t writes_ahead) const;
  // The same from the trigger's deadline on, any device (trigger_timeout 0).
  SafeTime safeAfterTrigger(size_t writes_ahead) const;

  // ---- start and stop: the one sequence the node and the simulation run ----
  // How the caller lets the bus work until every write of `writes` is done (allDone) or
  // `deadline` on the runtime's clock has passed: the node waits on the futures while the bus
  // thread runs; the simulation steps its bus on its manual clock. Returning earlier than both
  // is the caller's loss: what is not done then is reported as not confirmed in time.
  using AwaitWrites = std::function<void(const Pending& writes, Clock::time_point deadline)>;
  // One device's safe writes at the end of the wait: their result, or none (not done in time).
  struct WriteOutcome {
    std::string device;
    std::optional<Result> result;
  };
  using Outcomes = std::vector<WriteOutcome>;
  static bool allDone(const Pending& writes);
  static bool allDone(const Outcomes& outcomes);
  // s the start waits for its on_start safe writes beyond shutdown_timeout.
  static constexpr double kStartWriteGrace = 5.0;

  // The start (docs/failsafe.md F10): the bus starts (its thread, or stepping); the on_start safe
  // writes are queued, all at once, and awaited (all of them together: shutdown_timeout +
  // kStartWriteGrace); `before_commands` runs (no command or heartbeat was taken yet); then the
  // heartbeats count from now and the polls start.
  Outcomes start(const AwaitWrites& await, const std::function<void()>& before_commands = {});
  bool started() const { return started_; }
  // The stop (docs/failsafe.md F5): the share stops (queued requests refused unsent), then the
  // safe writes are queued, devices that answered first (a silent device's would hold the others
  // back), and awaited until shutdown_timeout from the stop's call.
  Outcomes stop(const AwaitWrites& await);
  // Ends the bus thread after stop(), waiting for its transaction until `grace` after the stop's
  // deadline: false when it is still in it (BusScheduler::stopBy).
  bool stopBus(Clock::duration grace);

  // ---- what the node carries for others ----
  // A raw write (write_registers, write_coils): refused unless allow_raw_writes, never a
  // broadcast; sent once (it may start something); confirmed or lost, the fail-safe learns it.
  std::future<Result> rawWrite(const Request& request, DeviceUnit::Call call = {});
  // Why no raw write may go to `slave` (raw writes off, or a broadcast); empty: it may.
  std::string rawWriteRefusal(uint8_t slave) const;
  // Bus thread: a share client's or raw write to `slave` (0: every device) went out.
  void externalWrite(const Request& request, const Result& result, CommandSource source);

  // Output writes and other jobs queued on the bus now.
  size_t queuedJobs() const { return scheduler_->queuedJobs(); }
  // The tag of the job on the bus now (BusScheduler::currentTag).
  uint64_t currentTag() const { return scheduler_->currentTag(); }

 private:
  std::vector<DeviceUnit*> answeringFirst() const;
  SafeTime busSafeTime() const;
  Pending applySafeEverywhere(Trigger trigger, const std::string& reason, bool only_on_start);
  static Outcomes outcomesOf(Pending& writes);

  BusConfig config_;
  Options options_;
  Clock& clock_;
  std::unique_ptr<BusScheduler> scheduler_;
  std::unique_ptr<Watchdog> bus_heartbeat_;
  std::vector<std::unique_ptr<DeviceUnit>> units_;
  std::map<uint8_t, DeviceUnit*> by_address_;
  std::unique_ptr<ShareGateway> share_;  // after the units: its jobs call into them
  double check_period_ = 0;
  SafeTime bus_safe_time_;  // safeAfterTrigger's parts from the configuration
  bool started_ = false;
  Clock::time_point stop_deadline_{};
};

}  // namespace modbus_rtu_driver
