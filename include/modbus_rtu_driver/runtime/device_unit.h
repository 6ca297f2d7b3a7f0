// One device on a bus, as the bus runtime wires it: the device object, its fail-safe (every
// device has one: its own heartbeat and command deadlines; a generic device's signals have safe
// values besides, GenericFailsafe) and its commands. This is the device's command API: each
// command is checked here (refused: a ready failure naming the field, nothing queued), queued
// here, told to the fail-safe with its outcome, read back here. The ROS adapter turns messages
// into these calls and publishes what the observers report; the fail-safe's simulation calls
// the same. ROS-free.
//
// Threads: commands come from any thread; observers run on the bus thread (report: on the
// thread that decided, the bus thread or the deadline timer's).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/core/bus/clock.h"
#include "modbus_rtu_driver/devices/device.h"
#include "modbus_rtu_driver/devices/ld58a08.h"
#include "modbus_rtu_driver/failsafe/device_commands.h"
#include "modbus_rtu_driver/failsafe/device_failsafe.h"
#include "modbus_rtu_driver/failsafe/generic_failsafe.h"
#include "modbus_rtu_driver/runtime/kept_timed_store.h"

namespace modbus_rtu_driver {

class GenericDevice;

class DeviceUnit {
 public:
  using Call = DeviceCommands::Call;
  using Done = DeviceCommands::Done;
  struct Observers {
    // Before each poll's first transaction.
    std::function<void()> poll_starting;
    // After each poll (`group`: a generic device's rate group, else 0) and the fail-safe's look
    // at it.
    std::function<void(size_t group, const Result&)> polled;
    // The device's state changed through a command or a safe write (outputs written, a timed
    // command or a signal written and read back): what the topics show is to be published.
    std::function<void()> changed;
    // A caller's output write the device confirmed, with every channel it carried (merged
    // writes included), right after its answer.
    OutputBatch::WrittenCallback written;
    // A fail-safe event and its words (FailsafeReport::text, or a generic device's).
    std::function<void(const FailsafeReport&, const std::string& text)> report;
  };

  DeviceUnit(std::shared_ptr<Device> device, BusScheduler& scheduler, Clock& clock);
  DeviceUnit(const DeviceUnit&) = delete;
  DeviceUnit& operator=(const DeviceUnit&) = delete;

  // Before the bus runs.
  void observe(Observers observers) { observers_ = std::move(observers); }

  Device& device() { return *device_; }
  const std::shared_ptr<Device>& sharedDevice() const { return device_; }
  const std::string& name() const { return device_->name(); }
  uint8_t address() const { return device_->address(); }
  DeviceFailsafe& failsafe() { return failsafe_; }
  const DeviceFailsafe& failsafe() const { return failsafe_; }
  // A generic device's safe values (nullptr for the other types).
  GenericFailsafe* genericSafe() { return generic_safe_.get(); }
  const GenericFailsafe* genericSafe() const { return generic_safe_.get(); }

  // ---- fail-safe (the runtime's trigger clock calls these) ----
  // Puts the channels with a safe state there (only those in `only`, when given), or a generic
  // device's signals at their safe values; the future holds the outcome.
  std::future<Result> applySafe(Trigger trigger, const std::string& reason,
                                const std::vector<uint8_t>& only = {});
  bool hasSafeStates() const;
  bool safeOnStart() const { return failsafe_.config().on_start_safe && hasSafeStates(); }
  // Command deadlines that passed, this device's own heartbeat: their safe writes.
  void checkDeadlines();
  // A write the node carried for someone else (share, raw) went out (bus thread).
  void externalWrite(const Request& request, const Result& result, CommandSource source) {
    failsafe_.externalWrite(request, result, source);
  }
  // The timed commands the previous node kept for this device resume here; this node's are
  // kept there from now on. Returns what resumed, in words ("" when nothing did). Before the
  // first poll.
  std::string keepTimedIn(KeptTimedStore& store);
  // Stops keeping (a node killed keeps nothing more).
  void stopKeeping() { keeping_ = false; }
  // Registers the device's polls (one, or one per generic rate group).
  void addPolls();

  // ---- commands ----
  // Outputs (SetBool, set_outputs): merged with every write queued meanwhile.
  std::future<Result> set(const std::vector<uint8_t>& channels, const std::vector<bool>& states,
                          Call call = {});
  // A command topic's message (the dead man's deadline, then the merged write): `call.done`
  // gets the outcome of the write that carried it.
  std::future<Result> command(uint8_t channel, bool state, Call call = {});
  // LC relay board: flash-close (state true) or flash-open for `seconds`.
  std::future<Result> pulse(uint8_t channel, bool state, double seconds, Call call = {});
  // LD58A08: a PWM run, and its stop.
  std::future<Result> setPwm(const PwmSettings& settings, Call call = {});
  std::future<Result> stopPwm(uint8_t channel, Call call = {});
  // Yespeed PDU: new limits, over-voltage and under-voltage in V and over-current in A, each 0 to
  // keep it. Each is checked against its range, and all three together against each other,
  // before the bus is asked; the device's limits are read back after the write (`limits()`).
  std::future<Result> setPduLimits(double over_voltage, double under_voltage, double over_current,
                                   Call call = {});
  // Generic device: signal `signal` to `value` (in its unit).
  std::future<Result> writeSignal(size_t signal, double value, Call call = {});

 private:
  GenericDevice* generic() const;
  void changed() const {
    if (observers_.changed) observers_.changed();
  }
  std::future<Result> refuse(const std::string& problem) const;

  std::shared_ptr<Device> device_;
  BusScheduler& scheduler_;
  DeviceFailsafe failsafe_;
  DeviceCommands commands_;                        // after failsafe_: it calls into it
  std::unique_ptr<GenericFailsafe> generic_safe_;  // generic devices
  Observers observers_;
  bool keeping_ = true;
};

}  // namespace modbus_rtu_driver
