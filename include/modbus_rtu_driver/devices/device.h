// One class per device type behind this interface. Device objects live on the bus thread:
// every method taking a Transport runs there (through BusScheduler), and the snapshot getters
// are read there too (in the scheduler's result callbacks).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/config/device_types.h"
#include "modbus_rtu_driver/core/config/signal.h"
#include "modbus_rtu_driver/core/link/transport.h"
#include "modbus_rtu_driver/core/modbus/types.h"
#include "modbus_rtu_driver/devices/failsafe.h"

namespace modbus_rtu_driver {

struct DeviceConfig {
  std::string name;                  // ROS namespace of the device under the node
  std::string type;                  // a registered type's name (devices/registry.h)
  int address = 1;                   // 1-255
  double poll_rate = 1.0;            // Hz, 0 = never poll
  std::vector<std::string> outputs;  // channel names; empty = out0..outN-1
  std::vector<std::string> inputs;   // channel names; empty = in0..inN-1
  double reply_delay = 0.0;          // s the device waits before answering (LD58A08 0x00FC x 40 ms)
  FailsafeConfig failsafe;           // safe states and when they apply
  SignalMapConfig generic;           // type generic: its signals (empty for the other types)
};

// A run of adjacent coils to write in one frame: coils first, first+1, ... get states.
struct CoilRun {
  uint8_t first = 0;
  std::vector<bool> states;
};
// `channels` / `states` as runs of adjacent channels, in channel order.
std::vector<CoilRun> coilRuns(const std::vector<uint8_t>& channels,
                              const std::vector<bool>& states);

// `given` when it has `n` names, else prefix0..prefix<n-1>.
std::vector<std::string> withDefaults(const std::vector<std::string>& given, size_t n,
                                      const char* prefix);

class OutputBatch;
class SelfTimedOutputs;

class Device {
  // The only writer of outputs (writeOutputs): every request checked once, then merged or alone.
  friend class OutputBatch;

 public:
  // `type`: the descriptor the type registered with (core/config/device_types/): its name and
  // channel counts are the device's, stated once.
  Device(const DeviceDescriptor& type, DeviceConfig config)
      : type_(type), config_(std::move(config)) {}
  virtual ~Device() = default;
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  const DeviceConfig& config() const { return config_; }
  uint8_t address() const { return static_cast<uint8_t>(config_.address); }
  const std::string& name() const { return config_.name; }

  const DeviceDescriptor& descriptor() const { return type_; }
  const char* type() const { return type_.name; }
  size_t outputCount() const { return type_.outputs; }
  size_t inputCount() const { return type_.inputs; }
  // The outputs it drives by itself for a time (self_timed_outputs.h: an LD58A08's PWM runs),
  // or none: every output then shows its coil.
  virtual SelfTimedOutputs* selfTimed() { return nullptr; }

  // Reads everything the device reports (outputs, inputs, telemetry, settings) into the
  // snapshot. On failure the snapshot keeps its previous values and the Result says why.
  virtual Result poll(Transport& link) = 0;
  // Empty when a write of channels[i] to states[i] is valid here (sizes match, each channel in
  // range and given once), else a message naming the field. OutputBatch checks every request
  // with it, once, before anything is queued.
  std::string checkOutputs(const std::vector<uint8_t>& channels,
                           const std::vector<bool>& states) const;

  // The outputs a client's confirmed write (a share client's, a raw write) set: FC05/FC15 on
  // the coils 0..outputCount()-1, which are the outputs of every fixed-function type. What other
  // writes do (a flash or PWM through registers) shows at the next poll.
  OutputTargets outputsWrittenBy(const Request& request) const;
  // The timed commands a client's confirmed register write started (an LC flash, an LD58A08 PWM
  // run), as the type decodes them; none for a type without any, or a write it cannot decode
  // (the fail-safe then takes what the next poll shows as commanded).
  virtual std::vector<TimedIntent> timedWrittenBy(const Request& request) const {
    (void)request;
    return {};
  }
  // Last confirmed states (from a poll or a confirmed write); empty until known.
  const std::vector<bool>& outputs() const { return outputs_; }
  const std::vector<bool>& inputs() const { return inputs_; }

  // Names for every channel, defaults filled in.
  std::vector<std::string> outputNames() const;
  std::vector<std::string> inputNames() const;

 protected:
  // The write of outputs OutputBatch has checked (checkOutputs), its only caller: it checks
  // nothing again. This one is for a board whose coils 0..N-1 are the outputs: FC05 for a lone
  // channel, FC15 per run of adjacent channels; a channel nobody asked for is never written.
  // Stops at the first run that fails (the message says which outputs were written before). A
  // lost answer is read back (confirmCoils). On success the snapshot holds the written states.
  // On failure, `changed` (if given) gets the channels the device confirmed changing before it
  // (the runs written before; an LD58A08's PWM runs stopped first): the fail-safe takes them as
  // found (docs/failsafe.md, "A write that failed after part of it was done").
  // `timed_may_run[c]`: a timed command (an LC flash, a PWM burst) may still drive channel c;
  // a read back cannot confirm a lost answer there (confirmCoils).
  virtual Result writeOutputs(Transport& link, const std::vector<uint8_t>& channels,
                              const std::vector<bool>& states,
                              std::vector<uint8_t>* changed = nullptr,
                              const std::vector<bool>& timed_may_run = {});
  // True for failures after which the device may have done the write (its reply was lost or
  // garbled), as opposed to refusing it or never being asked.
  static bool mayHaveActed(const Result& result);
  // After a failed coil write: reads the coils back; success if they show `states`, unless a
  // timed command may still drive one of the channels (`timed_may_run`): a plain write ends a
  // flash, and a read that shows the level cannot tell whether it did (docs/ros_api.md).
  Result confirmCoils(Transport& link, Result failed, const std::vector<uint8_t>& channels,
                      const std::vector<bool>& states, const std::vector<bool>& timed_may_run);

  std::vector<bool> outputs_;
  std::vector<bool> inputs_;

 private:
  const DeviceDescriptor& type_;
  DeviceConfig config_;
};

}  // namespace modbus_rtu_driver
