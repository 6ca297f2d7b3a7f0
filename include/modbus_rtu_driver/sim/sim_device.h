// A simulated slave: the register map and behaviour of one device type, driven by decoded
// requests and by time. ROS-free; one subclass per device type (sim/sim_<type>.h), which
// registers itself with the simulator (simDeviceClasses() in simulator.h). The line (simulator.h)
// decides which device hears a frame.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/config/device_types.h"
#include "modbus_rtu_driver/core/config/link_config.h"
#include "modbus_rtu_driver/core/modbus/frame.h"
#include "modbus_rtu_driver/core/modbus/types.h"

namespace YAML {
class Node;
}

namespace modbus_rtu_driver {

using SimClock = std::chrono::steady_clock;

// Serial settings: what a device listens and answers at, or what the line currently runs at.
struct SimLineSettings {
  int baud = 9600;
  Parity parity = Parity::kNone;
  int data_bits = 8;  // the line's; every simulated device uses 8
  int stop_bits = 1;  // the line's; a receiver accepts 1 or 2
};
// The line's timing, by the same rules as the driver's link (core/config/link_config.h).
int simBitsPerCharacter(const SimLineSettings& line);  // start, data, parity, stop
double simCharacterTime(const SimLineSettings& line);
double simFrameGap(const SimLineSettings& line);

class SimDevice {
 public:
  SimDevice(uint8_t address, SimLineSettings line) : address_(address), line_(line) {}
  virtual ~SimDevice() = default;

  virtual const char* type() const = 0;
  uint8_t address() const { return address_; }
  const SimLineSettings& line() const { return line_; }
  // A device only understands frames sent at its own baud and parity, 8 data bits.
  bool understands(const SimLineSettings& l) const {
    return l.baud == line_.baud && l.parity == line_.parity && l.data_bits == 8;
  }
  // Fault injection (control socket): answer nothing; answer every request with exception 04
  // (slave device failure); spoil the next N replies (bad CRC, cut short, another slave's
  // address, noise bytes after them, sent `late_ms` late); lose a share of the requests (not
  // heard, nothing done) or of the replies (done, the reply lost), in percent.
  bool silenced = false;
  bool failing = false;
  int corrupt_replies = 0;
  int truncate_replies = 0;
  int wrong_address_replies = 0;
  int noise_replies = 0;
  int late_replies = 0;
  int late_ms = 0;
  int drop_request_percent = 0;
  int drop_reply_percent = 0;
  // What happened to it: writes that changed its state or started something (a PWM burst, a
  // flash), requests it never heard and replies it lost by the drop faults.
  uint64_t changes = 0;
  uint64_t dropped_requests = 0;
  uint64_t dropped_replies = 0;

  // True when a frame with this slave byte is for this device (its address; some devices also
  // answer 0xFF). Broadcasts (0) are the line's business. `request` is null when the frame
  // could not be decoded.
  virtual bool answersTo(uint8_t slave, const Request* request) const {
    (void)request;
    return slave == address_;
  }
  // The reply (or exception) to a request for this device, or nothing (silence: broadcasts).
  std::optional<Bytes> handle(const Request& request, SimClock::time_point now);
  // A broadcast (slave 0) this device hears. The standard's rule: applied, never answered. A
  // device whose manual answers some broadcasts (the LC board's address commands) overrides it
  // and returns its reply; the line collides the replies of several such devices.
  virtual std::optional<Bytes> handleBroadcast(const Request& request, SimClock::time_point now) {
    handle(request, now);
    return std::nullopt;
  }
  // An exception reply for a request whose function this device does not know.
  Bytes unknownFunction(uint8_t slave, uint8_t function) const;
  // The longest read it serves (registers, or bits for `bits`); longer reads get exception 03,
  // as the protocol's limits do. Some devices serve less than the protocol allows.
  virtual uint16_t readLimit(bool bits) const {
    return maxCount(bits ? FunctionCode::kReadCoils : FunctionCode::kReadHoldingRegisters);
  }
  // Seconds the device waits before answering (LD58A08 return delay). Read before handling a
  // request: a new delay applies from the next one.
  virtual double replyDelay() const { return 0.0; }
  // Time-driven behaviour (PWM, flashes, telemetry). Reads and writes tick first themselves.
  virtual void tick(SimClock::time_point now) { (void)now; }
  // Power off and on: pending settings take effect, volatile state is lost.
  virtual void powerCycle(SimClock::time_point now) = 0;
  // Persistent state (what survives a power cycle) for the state file; loading it is a
  // power-on with that state.
  virtual void saveState(YAML::Node& node) const = 0;
  virtual void loadState(const YAML::Node& node, SimClock::time_point now) = 0;

  // True when this write starts something even if it leaves the registers as they were (a PWM
  // burst, a timed flash): a retry of it would do it twice.
  virtual bool startsSomething(const Request& request) const {
    (void)request;
    return false;
  }
  // One value; 0 or a Modbus exception code.
  virtual uint8_t read(Table table, uint16_t address, SimClock::time_point now,
                       uint16_t* value) = 0;
  // A whole write request (rules over several registers are checked together; a refused write
  // changes nothing). Coil values are 0/1.
  virtual uint8_t write(Table table, uint16_t address, const std::vector<uint16_t>& values,
                        SimClock::time_point now) = 0;
  // The control socket's `set`: state from outside the bus (inputs, telemetry pins); coils and
  // holding registers go through write().
  virtual uint8_t setDirect(Table table, uint16_t address, uint16_t value,
                            SimClock::time_point now);

 protected:
  bool wouldChange(const Request& request, SimClock::time_point now);

  uint8_t address_;
  SimLineSettings line_;
};

}  // namespace modbus_rtu_driver
