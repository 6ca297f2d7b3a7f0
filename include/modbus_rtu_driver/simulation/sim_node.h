// The node side of the deterministic simulation (ROS-free): what the bus node builds for one bus
// (the device classes, one DeviceFailsafe and DeviceCommands per device with outputs: the
// adapters' own write and timed-command jobs; the generic devices' safe values, the
// BusScheduler in step mode, the heartbeat's Watchdog, the share's and the raw writes' path)
// wired the way ros/bus_node.cpp and ros/device_adapter.cpp wire them, with the
// ROS parts (services, topics, timers) replaced by calls. Nothing here runs by itself: the
// simulation runs the bus (BusScheduler::step) and the deadline timer on one thread.
//
// Killing the node is destroying this object without stop(): no safe write is sent (what was
// queued fails unsent, as the kernel closing the port would leave it).
#pragma once

#include <cstdint>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/core/bus/watchdog.h"
#include "modbus_rtu_driver/devices/device.h"
#include "modbus_rtu_driver/devices/ld58a08.h"
#include "modbus_rtu_driver/failsafe/device_commands.h"
#include "modbus_rtu_driver/failsafe/device_failsafe.h"
#include "modbus_rtu_driver/failsafe/generic_failsafe.h"
#include "modbus_rtu_driver/failsafe/kept_timed_commands.h"

namespace modbus_rtu_driver {

struct SimNodeOptions {
  std::vector<DeviceConfig> devices;
  double heartbeat_timeout = 0.5;  // the bus heartbeat; 0 = none
  double shutdown_timeout = 3.0;
  BusScheduler::Options scheduling;
  // The parameter server's running_timed/<device> (DeviceAdapter::keepTimedIn):
  // owned by the harness, so it outlives a killed or stopped node; ends in the clock's seconds.
  // Null: nothing kept.
  std::map<std::string, std::vector<KeptTimedCommand>>* kept_timed = nullptr;
};

struct SimNodeHooks {
  // Every fail-safe report (generic devices' included), as ~failsafe would publish it.
  std::function<void(const FailsafeReport&)> report;
  // Before each poll's first transaction (bus thread).
  std::function<void(const std::string& device)> poll_starting;
  // After each poll and the fail-safe's look at it (bus thread).
  std::function<void(const std::string& device, const Result&)> polled;
  // A user's output write (service or topic, merged writes included) the device confirmed, as
  // OutputBatch reports it (bus thread, right after the device's answer).
  std::function<void(const std::string& device, const std::vector<uint8_t>& channels,
                     const std::vector<bool>& states)>
      written;
};

class SimNode {
 public:
  SimNode(SimNodeOptions options, Transport& transport, Clock& clock, SimNodeHooks hooks);
  ~SimNode();

  // BusNode::start in two halves, as the bus must run in between: the on_start safe writes are
  // queued; once startWritesDone(), finishStart() arms the heartbeats and adds the polls (from
  // then on commands are taken).
  void beginStart();
  bool startWritesDone() const;
  void finishStart();
  bool started() const { return started_; }

  // BusNode::shutdown in two halves: the share closes, the safe writes are queued (devices
  // that answered first); stopWritesDone() says when all are done; then destroy the node.
  void beginStop();
  bool stopWritesDone() const;

  BusScheduler& scheduler() { return *scheduler_; }
  // The deadline timer's period (a tenth of the shortest timeout, at most 0.5 s; 0: no timer).
  double checkPeriod() const { return check_period_; }
  // Output writes and other jobs queued on the bus now (the docs' timing counts one
  // transaction for each write ahead of a safe write).
  size_t queuedJobs() const;
  void checkDeadlines();                                // BusNode::checkDeadlines
  void feedHeartbeat();                                 // a message on the heartbeat topic
  void feedDeviceHeartbeat(const std::string& device);  // on a device's own heartbeat topic
  bool heartbeatLost() const { return heartbeat_ && heartbeat_->tripped(); }

  // The operation whose bus job runs now (0: none, i.e. the fail-safe's own or a poll).
  uint64_t currentOp() const { return current_op_; }

  // Commands, as the services and topics give them (checked first, as they are). `done` runs
  // on the bus thread right after the device's answer, before any other job.
  using Done = std::function<void(const Result&)>;
  std::future<Result> set(uint64_t op, const std::string& device,
                          const std::vector<uint8_t>& channels, const std::vector<bool>& states,
                          Done done);
  // C/command: the dead man's deadline, the merged write.
  std::future<Result> command(uint64_t op, const std::string& device, uint8_t channel, bool state,
                              Done done);
  std::future<Result> pulse(uint64_t op, const std::string& device, uint8_t channel, bool state,
                            double duration, Done done);
  std::future<Result> setPwm(uint64_t op, const std::string& device, const PwmSettings& s,
                             Done done);
  std::future<Result> stopPwm(uint64_t op, const std::string& device, uint8_t channel, Done done);
  // A share client's request (ShareGateway's path: sent once, a confirmed write is
  // externalWrite) and a raw write (RawWrites's path).
  std::future<Result> share(uint64_t op, const Request& request, Done done);
  std::future<Result> raw(uint64_t op, const Request& request, Done done);
  std::future<Result> writeSignal(uint64_t op, const std::string& device, size_t signal,
                                  double value, Done done);

  Device* device(const std::string& name);
  DeviceFailsafe* failsafe(const std::string& name);

 private:
  struct Entry {
    std::shared_ptr<Device> device;
    std::unique_ptr<DeviceFailsafe> failsafe;       // devices with outputs
    std::unique_ptr<DeviceCommands> commands;       // devices with outputs
    std::unique_ptr<GenericFailsafe> generic_safe;  // generic devices: their safe values
  };
  Entry* entry(const std::string& name);
  void keepTimed(Entry& e);
  std::vector<Entry*> answeringFirst();
  std::future<Result> applySafe(Entry& e, const std::string& trigger, const std::string& reason);
  // Runs `call` (one DeviceCommands call) so that the job it queues, if any, runs for `op` and
  // tells `done`.
  std::future<Result> viaCommands(uint64_t op, Done done,
                                  const std::function<std::future<Result>()>& call);
  void externalWrite(const Request& request, const Result& result, CommandSource source);
  std::future<Result> runOp(uint64_t op, const std::string& device, Done done,
                            std::function<Result(Transport&)> job);

  SimNodeOptions options_;
  Clock& clock_;
  SimNodeHooks hooks_;
  std::unique_ptr<BusScheduler> scheduler_;
  std::vector<std::unique_ptr<Entry>> entries_;
  std::unique_ptr<Watchdog> heartbeat_;
  double check_period_ = 0;
  bool started_ = false;
  bool share_closed_ = false;
  bool killed_ = false;  // SIGKILL runs no code: nothing more is kept
  uint64_t current_op_ = 0;
  uint64_t submitting_op_ = 0;  // viaCommands: the operation and callback of the job queued now
  Done submitting_done_;
  std::vector<std::future<Result>> start_writes_, stop_writes_;
};

}  // namespace modbus_rtu_driver
