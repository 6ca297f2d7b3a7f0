// Output writes to one device that queue up while the bus is busy, merged into one write.
// Every caller adds its request and queues a bus job; the first of those jobs to run writes
// everything pending at that moment with one write of the device (FC05 for a lone channel, FC15
// per run of adjacent channels; no other channel is written), newest state per channel winning, and
// every merged caller gets that outcome. The later jobs find their request done and send nothing.
// A request is checked once, as it is added; the merged write is made of checked ones only.
// Every write of a device's outputs goes through here (Device::writeOutputs has no other caller):
// the fail-safe's own writes too, alone (write()). ROS-free.
#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "modbus_rtu_driver/devices/device.h"

namespace modbus_rtu_driver {

class OutputBatch {
 public:
  struct Entry {
    std::vector<uint8_t> channels;
    std::vector<bool> states;
    std::optional<Result> result;  // set on the bus thread once written (or refused)
  };

  // Any thread: adds a request to the next write of `device`, checking it (Device::checkOutputs)
  // here and only here. A refused request is not added: its entry comes back with its
  // kInvalidArgument result set, and needs no bus job.
  std::shared_ptr<Entry> add(const Device& device, std::vector<uint8_t> channels,
                             std::vector<bool> states);
  // What a confirmed write set: channels[i] to states[i] (newest state per channel).
  using WrittenCallback =
      std::function<void(const std::vector<uint8_t>& channels, const std::vector<bool>& states)>;

  // What a write that was sent but not confirmed carried: every channel merged into it (the
  // callers of each were told it failed; the device may have acted on any of them), and those
  // the device confirmed changing before it failed (Device::writeOutputs's `changed`).
  using NotConfirmedCallback =
      std::function<void(const std::vector<uint8_t>& channels, const Result& result,
                         const std::vector<uint8_t>& changed)>;

  // Bus thread: one request written alone, now, merged with nothing pending: checked as add()
  // checks it (a refused one is not sent). For writes that must carry exactly what they name
  // (the fail-safe's safe states; a caller with a bus job of its own).
  // `timed_may_run`: as for Device::writeOutputs (the channels a timed command may still drive).
  static Result write(Device& device, Transport& link, const std::vector<uint8_t>& channels,
                      const std::vector<bool>& states, const std::vector<bool>& timed_may_run = {});

  // Bus thread: the outcome of `entry`, writing the pending requests first if it is among them.
  // `device` is the one they were added for. `on_written` runs once per confirmed write,
  // `on_not_confirmed` once per write that failed.
  Result complete(Device& device, Transport& link, const std::shared_ptr<Entry>& entry,
                  const WrittenCallback& on_written = {},
                  const NotConfirmedCallback& on_not_confirmed = {},
                  const std::vector<bool>& timed_may_run = {});

 private:
  std::mutex mutex_;
  std::vector<std::shared_ptr<Entry>> pending_;
};

}  // namespace modbus_rtu_driver
