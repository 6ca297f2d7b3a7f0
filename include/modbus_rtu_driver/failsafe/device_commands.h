// One device's callers' commands on their way to the bus: a service's write of outputs, a command
// topic's message, a timed command (an LC flash, an LD58A08 PWM run or its stop). Each is
// checked before anything is queued, runs as one bus job, is written through OutputBatch (merged
// with the writes queued meanwhile), and its outcome goes to the fail-safe, which decides what
// the channel should be from then on. The bus runtime's DeviceUnit calls it (runtime/), for the
// ROS adapters and the fail-safe's simulation alike. ROS-free.
//
// Threads: every call comes from any thread; `done`, `after` and the written callback run on
// the bus thread, in the job, right after the device's answer.
#pragma once

#include <cstdint>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <vector>

#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/devices/device.h"
#include "modbus_rtu_driver/devices/output_batch.h"
#include "modbus_rtu_driver/failsafe/device_failsafe.h"

namespace modbus_rtu_driver {

// Who asks for a command: `tag` names the caller's operation on the bus (BusScheduler::currentTag
// while its job runs; 0: none); `done` gets the outcome on the bus thread at the job's end,
// before any other job runs (the simulation's model learns it there).
struct CommandCall {
  uint64_t tag = 0;
  std::function<void(const Result&)> done;
};

class DeviceCommands {
 public:
  using Done = std::function<void(const Result&)>;
  using After = std::function<void(Transport&)>;
  using Call = CommandCall;

  DeviceCommands(Device& device, DeviceFailsafe& failsafe, BusScheduler& scheduler);
  DeviceCommands(const DeviceCommands&) = delete;
  DeviceCommands& operator=(const DeviceCommands&) = delete;

  // Runs after each write of callers' outputs that the device confirmed, with every channel it
  // carried (the adapter publishes the outputs); before the bus runs.
  void setWritten(OutputBatch::WrittenCallback written) { written_ = std::move(written); }

  // A service's write: checked here (refused: a ready failure, nothing queued), then written with
  // every other write queued for the device meanwhile (newest state per channel wins).
  std::future<Result> write(const std::vector<uint8_t>& channels, const std::vector<bool>& states,
                            Call call = {});
  // A command topic's message: the dead man's deadline, then the same merged write. One bus job
  // at a time is queued for commands: it writes the newest command and every one added before.
  // `done` gets the outcome of the write that carried this command. The future is that job's
  // when this call queued it; a ready success when the command joined a queued job (its outcome
  // comes through `call.done`, also when it joined a queued job); a ready failure when refused.
  std::future<Result> command(uint8_t channel, bool state, Call call = {});
  // A timed command the device runs by itself (`intent`: its channel, level during and after,
  // seconds): `send` writes it; confirmed, it is the caller's command, whose end and final level
  // the fail-safe knows; not confirmed, the channel may run it or not until its end. `after`
  // runs after a confirmed one (the adapters read the outputs back and publish them).
  std::future<Result> timed(const TimedIntent& intent, BusScheduler::Job send, After after = {},
                            Call call = {});
  // A run the device times by itself stopped on `channel` (stop_pwm): confirmed, the channel
  // shows its level again, taken at the next poll; its answer lost, unknown until a poll reads
  // it.
  std::future<Result> stopTimed(uint8_t channel, BusScheduler::Job send, After after = {},
                                Call call = {});

 private:
  // Bus thread: the outcome of `entry`, written with every other pending one if not written
  // yet; confirmed or not, every channel the write carried reaches the fail-safe.
  Result complete(Transport& t, const std::shared_ptr<OutputBatch::Entry>& entry);
  // The job of a timed command or its stop: `send`, its outcome to the fail-safe (`tell`), then
  // `after` when confirmed.
  std::future<Result> timedJob(BusScheduler::Job send, After after, Done tell, Call call);
  // Queues `job` for this device, tagged, `done` told at its end.
  std::future<Result> submit(BusScheduler::Job job, Call call);

  Device& device_;
  DeviceFailsafe& failsafe_;
  BusScheduler& scheduler_;
  OutputBatch::WrittenCallback written_;
  OutputBatch batch_;  // service writes and command topics, merged

  std::mutex commands_mutex_;  // the three below
  std::shared_ptr<OutputBatch::Entry> newest_command_;
  bool command_job_queued_ = false;
  std::vector<Done> command_done_;  // the queued job's commands, in the order they came
};

}  // namespace modbus_rtu_driver
