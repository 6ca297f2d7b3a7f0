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
  // True for an output the device drives by itself right now (a running PWM), as far as the
  // snapshot knows: a poll that shows it changed is not a restart.
  virtual bool outputSelfTimed(size_t channel) const {
    (void)channel;
    return false;
  }
  // Whether the newest poll read what outputSelfTimed() answers for the channel (an LD58A08
  // reads one channel's PWM registers per poll; the others are older).
  virtual bool selfTimedReadByLastPoll(size_t channel) const {
    (void)channel;
    return true;
  }
  // Bus thread: the next polls read these channels' self-timed state first (an LD58A08 reads
  // one channel's PWM registers per poll): the fail-safe waits for it to decide them.
  virtual void readSelfTimedFirst(const std::vector<uint8_t>& channels) { (void)channels; }
  // Whether outputSelfTimed() answers from what was read (false while an LD58A08's PWM registers
  // were never read: it then answers true for every channel, "may run").
  virtual bool selfTimedRead() const { return true; }

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
  // The channels whose timed command a client's confirmed register write stopped (an LD58A08
  // enable register written 0): each shows its coil again, taken at the next poll.
  virtual std::vector<uint8_t> timedStoppedBy(const Request& request) const {
    (void)request;
    return {};
  }
  // Bus thread: a write the node carried for someone else (a share client, a raw write) was
  // confirmed; what it set is the device's state now (an LD58A08's PWM snapshot, otherwise
  // read one channel per poll, would say so only polls later).
  virtual void noteCarriedWrite(const Request& request) { (void)request; }
  // Whether a coil write leaves a run the device times by itself going (an LD58A08's PWM: its
  // outputs apply only with the channel's enable register at 0).
  virtual bool coilWriteKeepsRun() const { return false; }
  // Bus thread: a coil write the device confirmed on `channel` kept a run going there (per
  // coilWriteKeepsRun and what the node knew of it): the snapshot says it runs until a read says
  // otherwise, as a read showing it would.
  virtual void noteRunKept(uint8_t channel) { (void)channel; }
  // Starts a continuous run again with the write that started it (TimedIntent::restart): a
  // restore after a power cycle stopped it. Sent once; a lost answer is read back.
  virtual Result startAgain(Transport& link, const Request& write) {
    (void)link;
    return Result::failure(
        ErrorKind::kInvalidArgument,
        std::string("a ") + type() + " has no run to start again: " + write.describe());
  }
  // Reads again what outputSelfTimed() answers from (an LD58A08's PWM registers, otherwise
  // read one channel per poll), so a restore decides on the device's state now.
  virtual Result refreshSelfTimed(Transport& link) {
    (void)link;
    return Result::success();
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
