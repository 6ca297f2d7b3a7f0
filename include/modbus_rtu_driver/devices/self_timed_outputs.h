// Outputs a device drives by itself for a time it was given (an LD58A08's PWM runs: bursts,
// timed and continuous runs): what the fail-safe must know of them beyond the coils. A device
// type with such outputs implements this and returns itself from Device::selfTimed(); the others
// (the LC board, whose flash ends by itself but shows in its coils; the PDU; generic devices)
// have none, and the fail-safe then takes every output as showing its coil.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "modbus_rtu_driver/core/link/transport.h"
#include "modbus_rtu_driver/core/modbus/types.h"

namespace modbus_rtu_driver {

class SelfTimedOutputs {
 public:
  virtual ~SelfTimedOutputs() = default;

  // ---- what the last reads showed ----
  // True for an output the device drives by itself right now, as far as the snapshot knows: a
  // poll that shows it changed is not a restart.
  virtual bool outputSelfTimed(size_t channel) const = 0;
  // Whether the newest poll read what outputSelfTimed() answers for the channel (an LD58A08
  // reads one channel's PWM registers per poll; the others are older).
  virtual bool selfTimedReadByLastPoll(size_t channel) const = 0;
  // Whether outputSelfTimed() answers from what was read (false while the runs were never read:
  // it then answers true for every channel, "may run").
  virtual bool selfTimedRead() const = 0;
  // Bus thread: the next polls read these channels' runs first: the fail-safe waits for them to
  // decide those channels.
  virtual void readSelfTimedFirst(const std::vector<uint8_t>& channels) = 0;
  // Reads again every channel's run, so that a restore decides on the device's state now.
  virtual Result refreshSelfTimed(Transport& link) = 0;

  // ---- writes and runs ----
  // Whether a coil write leaves a run going (an LD58A08's outputs apply only with the channel's
  // enable register at 0).
  virtual bool coilWriteKeepsRun() const = 0;
  // Bus thread: a coil write the device confirmed on `channel` kept a run going there: the
  // snapshot says it runs until a read says otherwise, as a read showing it would.
  virtual void noteRunKept(uint8_t channel) = 0;
  // The channels whose run a client's confirmed register write stopped (an LD58A08 enable
  // register written 0): each shows its coil again, taken at the next poll.
  virtual std::vector<uint8_t> timedStoppedBy(const Request& request) const = 0;
  // Bus thread: a write the node carried for someone else (a share client, a raw write) was
  // confirmed; what it set is the device's state now (the run snapshot, otherwise read one
  // channel per poll, would say so only polls later).
  virtual void noteCarriedWrite(const Request& request) = 0;
  // Starts a continuous run again with the write that started it (TimedIntent::restart): a
  // restore after a power cycle stopped it. Sent once; a lost answer is read back.
  virtual Result startAgain(Transport& link, const Request& write) = 0;
};

}  // namespace modbus_rtu_driver
