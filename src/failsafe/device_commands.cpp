#include "modbus_rtu_driver/failsafe/device_commands.h"

namespace modbus_rtu_driver {

DeviceCommands::DeviceCommands(Device& device, DeviceFailsafe& failsafe, BusScheduler& scheduler)
    : device_(device), failsafe_(failsafe), scheduler_(scheduler) {}

std::future<Result> DeviceCommands::submit(BusScheduler::Job job, Call call) {
  if (!call.done) return scheduler_.submit(device_.name(), std::move(job), call.tag);
  return scheduler_.submit(
      device_.name(),
      [job = std::move(job), done = std::move(call.done)](Transport& t) {
        Result r = job(t);
        done(r);
        return r;
      },
      call.tag);
}

std::future<Result> DeviceCommands::write(const std::vector<uint8_t>& channels,
                                          const std::vector<bool>& states, Call call) {
  auto entry = batch_.add(device_, channels, states);  // checked there, once
  if (const std::optional<Result>& refused = entry->result) return readyResult(*refused);
  return submit([this, entry](Transport& t) { return complete(t, entry); }, std::move(call));
}

std::future<Result> DeviceCommands::command(uint8_t channel, bool state, Call call) {
  Done done = std::move(call.done);
  failsafe_.commandReceived(channel, state);  // the dead man's deadline
  std::lock_guard<std::mutex> lock(commands_mutex_);
  auto entry = batch_.add(device_, {channel}, {state});
  if (const std::optional<Result>& refused = entry->result) {
    // Refused (never, for a channel a topic subscribes for).
    if (done) done(*refused);
    return readyResult(*refused);
  }
  newest_command_ = std::move(entry);
  command_done_.push_back(std::move(done));
  if (command_job_queued_) return readyResult(Result::success());  // the queued job takes it
  command_job_queued_ = true;
  return submit(
      [this](Transport& t) {
        std::shared_ptr<OutputBatch::Entry> newest;
        std::vector<Done> dones;
        {
          std::lock_guard<std::mutex> lock(commands_mutex_);
          newest = std::move(newest_command_);
          dones.swap(command_done_);
          command_job_queued_ = false;
        }
        Result w = complete(t, newest);
        for (const Done& d : dones)
          if (d) d(w);
        return w;
      },
      {call.tag, {}});
}

Result DeviceCommands::complete(Transport& t, const std::shared_ptr<OutputBatch::Entry>& entry) {
  if (!entry->result) failsafe_.userWriteSending();  // this job sends the pending writes
  // Outcomes per merged write: every channel it carried, not only this entry's.
  return batch_.complete(
      device_, t, entry,
      [this](const std::vector<uint8_t>& channels, const std::vector<bool>& states) {
        failsafe_.userWriteConfirmed(channels, states);
        if (written_) written_(channels, states);
      },
      [this](const std::vector<uint8_t>& channels, const Result& result,
             const std::vector<uint8_t>& changed) {
        failsafe_.userWriteNotConfirmed(channels, result, changed);
      },
      failsafe_.timedMayRun());
}

std::future<Result> DeviceCommands::timed(const TimedIntent& intent, BusScheduler::Job send,
                                          After after, Call call) {
  return timedJob(
      std::move(send), std::move(after),
      [this, intent](const Result& w) { failsafe_.timedCommandDone(intent, w); }, std::move(call));
}

std::future<Result> DeviceCommands::stopTimed(uint8_t channel, BusScheduler::Job send, After after,
                                              Call call) {
  return timedJob(
      std::move(send), std::move(after),
      [this, channel](const Result& w) { failsafe_.timedCommandStopped(channel, w); },
      std::move(call));
}

std::future<Result> DeviceCommands::timedJob(BusScheduler::Job send, After after, Done tell,
                                             Call call) {
  return submit(
      [this, send = std::move(send), after = std::move(after),
       tell = std::move(tell)](Transport& t) {
        failsafe_.timedCommandSending();
        Result w = send(t);
        tell(w);
        if (w.ok() && after) after(t);
        return w;
      },
      std::move(call));
}

}  // namespace modbus_rtu_driver
