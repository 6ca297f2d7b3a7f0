// Any Modbus device described in YAML (type `generic`): a list of signals, each a bit or a
// number in one of the four tables. Signals are polled in groups by rate (group 0 at the
// device's poll_rate, one group per other rate), with merged reads (signal_map.h). Writable
// signals are written with their write_function (by default FC05 for a coil, FC06 for one
// register, FC16 for several; FC15 / FC16 for devices without the single writes), confirmed by
// the echo, or by reading back when the reply was lost.
#pragma once

#include <chrono>
#include <deque>
#include <mutex>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/config/device_types/generic.h"
#include "modbus_rtu_driver/devices/device.h"
#include "modbus_rtu_driver/devices/signal_map.h"

namespace modbus_rtu_driver {

struct SignalState {
  double value = 0.0;  // engineering units (bits: 0 or 1)
  bool valid = false;  // the last read of it succeeded
  bool known = false;  // it was read (or written) at least once
};

// Whether a reading is the one already published: equal, or both NaN (a float32 register
// holding NaN reads NaN on every poll, and NaN != NaN would publish it every time).
bool sameReading(double a, double b);

class GenericDevice : public Device {
 public:
  struct PollGroup {
    double rate = 0.0;            // Hz
    std::vector<size_t> signals;  // indices into signals()
  };

  explicit GenericDevice(DeviceConfig config);

  // Reads group 0 (the signals at the device's own poll_rate).
  Result poll(Transport& link) override { return pollGroup(link, 0); }
  const std::vector<SignalConfig>& signals() const { return planner_.signals(); }
  const std::vector<SignalState>& states() const { return states_; }
  // Group 0 always exists (it may be empty); one more per distinct signal poll_rate.
  const std::vector<PollGroup>& groups() const { return groups_; }
  // Reads the group's signals. A span refused with exception 02 or 03 is split and both parts
  // read again at once. Signals whose read failed turn invalid; the Result is the first failure.
  Result pollGroup(Transport& link, size_t group);

  // The registers (or the bit) that `value` of `signal` becomes, or a message naming the
  // signal and the allowed range (min/max, then the type's, then min/max again for the value
  // the rounded raw number stands for). Nothing is sent here.
  std::string encodeWrite(size_t signal, double value, std::vector<uint16_t>* words) const;
  // Checks (encodeWrite), writes and confirms; on success the state holds the written value.
  Result writeSignal(Transport& link, size_t signal, double value);

  // Fail-safe: the signals with a safe_value (indices), in configuration order.
  std::vector<size_t> safeSignals() const;
  // Writes the safe_value of each of `signals` (safe signals) and reads it back (the value on
  // the device, not the write's echo), in order. A refusal does not stop the others; a device
  // that does not answer does (the rest would only wait out their timeouts). The Result is the
  // first failure, its message naming the signal; the states hold what was read back.
  // `not_reached` (when given): the signals whose safe value the device may not have got
  // because it stopped answering (the one it went silent on and those not tried); a value it
  // refused or did not keep (read back differs) is its answer, not in it.
  Result writeSafeValues(Transport& link, const std::vector<size_t>& signals,
                         std::vector<size_t>* not_reached = nullptr);

  // Merged spans split after exception 02 or 03, in words (diagnostics).
  const std::vector<std::string>& splits() const { return planner_.splits(); }

 private:
  // Reads one span; false when the device did not answer (the rest of the poll is skipped).
  bool readSpan(Transport& link, const ReadSpan& span, Result* first_failure);
  // The write of `words` (encodeWrite's) with the signal's write function.
  Request writeRequest(const SignalConfig& s, const std::vector<uint16_t>& words) const;
  void setFromWords(size_t signal, const uint16_t* words);
  // `answered`: the device answered every transaction (a refusal or a value not kept included).
  Result writeSafeValue(Transport& link, size_t signal, bool* answered);

  ReadPlanner planner_;
  std::vector<PollGroup> groups_;
  std::vector<SignalState> states_;
};

}  // namespace modbus_rtu_driver
