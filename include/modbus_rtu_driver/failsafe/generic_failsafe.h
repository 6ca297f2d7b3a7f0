// A generic device's fail-safe, ROS-free: its signals' safe values stand for the outputs' safe
// states (docs/failsafe.md, "Generic devices"). The triggers are the node's and the adapter's
// (shutdown, heartbeat, on_start, a device heartbeat); this class writes every safe value, reads
// each back, reports what it did, and writes them again once a device that was silent answers
// a poll. It also carries the user's writes (write()): a signal set since a trigger fired is not
// written safe by that trigger, now or later (docs/failsafe.md, "Generic devices"). No restart
// detection and no on_restart: a generic device's signals say nothing of it. The bus runtime's
// DeviceUnit owns it (runtime/device_unit.h), for the node and the simulation alike.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <future>
#include <mutex>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/devices/generic_device.h"
#include "modbus_rtu_driver/failsafe/device_failsafe.h"

namespace modbus_rtu_driver {

class GenericFailsafe {
 public:
  using ReportSink = std::function<void(const FailsafeReport&)>;

  GenericFailsafe(GenericDevice& device, BusScheduler& scheduler);
  GenericFailsafe(const GenericFailsafe&) = delete;
  GenericFailsafe& operator=(const GenericFailsafe&) = delete;

  // Where reports go (their channels are the signals, `values` their safe values), and what to
  // run on the bus thread after a safe write changed the signals (the adapter publishes them);
  // before the bus runs.
  void setReportSink(ReportSink sink) { sink_ = std::move(sink); }
  void setSignalsWritten(std::function<void()> written) { written_ = std::move(written); }

  bool hasSafeValues() const { return !device_.safeSignals().empty(); }
  // Any thread: the trigger fires now. Writes every safe value of a signal not set since, and
  // reads each back (a bus job), then reports. The future holds the outcome (a ready success
  // with no safe value).
  std::future<Result> applySafe(Trigger trigger, const std::string& reason);
  // Bus thread, after each poll: safe values not reached because the device did not answer
  // are written once it answers (one try per answer; a refusal is an answer and not retried),
  // except on a signal set since their trigger fired.
  void afterPoll(const Result& poll);
  // Bus thread: a user's write of `signal` (GenericDevice::writeSignal). Confirmed, it is newer
  // than every trigger so far, and the signals are no longer "at their safe values".
  Result write(Transport& t, size_t signal, double value);

  // "speed 0 rpm", "run off": a safe value as the reports and /diagnostics say it.
  std::string describeSafeValue(size_t signal) const;
  // "heartbeat (why): run off, speed 0 rpm[; NOT confirmed: why]"
  std::string text(const FailsafeReport& report) const;

  struct Status {
    uint64_t events = 0;
    std::string last_event;  // the newest report in words, or ""
    std::string active;      // the newest safe write's, until a user's write; or ""
  };
  Status status() const;

 private:
  // Bus thread: the safe values of the safe signals not set since `fired` written and read
  // back, the report made (none when every one was set since).
  Result writeSafe(Transport& t, Trigger trigger, const std::string& reason, uint64_t fired,
                   const std::vector<size_t>& signals);

  GenericDevice& device_;
  BusScheduler& scheduler_;
  ReportSink sink_;
  std::function<void()> written_;
  // Triggers and confirmed sets in the order they happened: each takes the next number.
  std::atomic<uint64_t> sequence_{0};
  // Bus thread only, per signal: the number of the newest confirmed set (0: none), and of the
  // trigger whose safe value the device did not get because it was silent (0: none owed).
  std::vector<uint64_t> set_at_;
  std::vector<uint64_t> owed_since_;

  mutable std::mutex mutex_;  // status_
  Status status_;
};

}  // namespace modbus_rtu_driver
