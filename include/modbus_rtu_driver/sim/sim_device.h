// A simulated slave: the register map and behaviour of one device type, driven by decoded
// requests and by time. ROS-free; one subclass per device type.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/frame.h"
#include "modbus_rtu_driver/core/types.h"

namespace YAML {
class Node;
}

namespace modbus_rtu_driver {

enum class Table { kCoil, kDiscreteInput, kHolding, kInputRegister };
bool parseTable(const std::string& name, Table* out);  // coil, input, holding, ireg

using SimClock = std::chrono::steady_clock;

// What the simulated line settings of a device are (what it listens and answers at).
struct SimLineSettings {
  int baud = 9600;
  char parity = 'N';  // N, E, O
};

class SimDevice {
 public:
  SimDevice(uint8_t address, SimLineSettings line) : address_(address), line_(line) {}
  virtual ~SimDevice() = default;

  virtual const char* type() const = 0;
  uint8_t address() const { return address_; }
  const SimLineSettings& line() const { return line_; }
  // Fault injection (control socket): answer nothing; corrupt the CRC of the next N replies;
  // answer every request with exception 04 (slave device failure).
  bool silenced = false;
  int corrupt_replies = 0;
  bool failing = false;

  // True when a frame with this slave byte is for this device (its address; some devices also
  // answer 0xFF or address 0 commands). Broadcast writes (0) reach every device anyway.
  // `request` is null when the frame could not be decoded (unknown function).
  virtual bool answersTo(uint8_t slave, const Request* request) const {
    (void)request;
    return slave == address_;
  }
  // The reply to a request for this device (or a broadcast), or nothing (silence).
  std::optional<Bytes> handle(const Request& request, SimClock::time_point now);
  // An exception reply for a request whose function this device does not know.
  Bytes unknownFunction(uint8_t slave, uint8_t function) const;
  // How long the device waits before answering (LD58A08 return delay).
  virtual double replyDelay() const { return 0.0; }
  // Time-driven behaviour (PWM, flashes, telemetry).
  virtual void tick(SimClock::time_point now) { (void)now; }
  // Power off and on: pending settings take effect, volatile state is lost.
  virtual void powerCycle() = 0;
  // Persistent state (what survives a power cycle) for the state file.
  virtual void saveState(YAML::Node& node) const = 0;
  virtual void loadState(const YAML::Node& node) = 0;

  // One value; 0 or a Modbus exception code.
  virtual uint8_t read(Table table, uint16_t address, SimClock::time_point now,
                       uint16_t* value) = 0;
  // A whole write request (so rules over several registers can be checked together).
  virtual uint8_t write(Table table, uint16_t address, const std::vector<uint16_t>& values,
                        SimClock::time_point now) = 0;
  // The control socket's `set`: sets state from outside the bus (inputs, telemetry pins).
  virtual uint8_t setDirect(Table table, uint16_t address, uint16_t value,
                            SimClock::time_point now);

 protected:
  uint8_t address_;
  SimLineSettings line_;
};

// Builds a device of `type` (ld58a08, lc_relay8, yespeed_pdu); null for an unknown type.
std::unique_ptr<SimDevice> makeSimDevice(const std::string& type, uint8_t address,
                                         SimLineSettings line);

}  // namespace modbus_rtu_driver
