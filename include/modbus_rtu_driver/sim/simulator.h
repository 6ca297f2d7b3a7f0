// The simulated RS485 line: a pseudo-terminal whose slave side is linked at a path the driver
// opens like a serial port, several SimDevices on it, a control socket for tests, a power cycle
// and a state file. One thread runs the line, the devices and the control socket, so devices
// need no locks of their own; the in-process API (command) takes the same mutex.
//
// The line: bytes are cut into frames by the length their header announces; what does not form
// a valid frame is dropped when the line has been silent for t3.5 (at least 4 ms: a pty delivers
// in bursts). A device hears a frame only at its own baud and parity (what the client set on the
// pty); frames for nobody, and frames with a bad CRC, get silence. Every device that takes a
// frame answers it: an LD58A08 taking a frame at 0xFF (for itself) beside an LC board at its
// factory address 255 means two replies at once, which collide (collideReplies). Broadcasts
// (address 0) reach every device and nobody answers, except the LC board's address commands at 0:
// every LC board takes them and answers, and two or more replies collide into garbled bytes
// (collideReplies), as on a real bus. Other devices see the LC address command as a broadcast write
// to their register 0 (LD58A08: channel 0's period; PDU: its over-voltage limit, refused below 180
// V). With `pace`, the reply starts t3.5 after the request's wire time and its bytes are written at
// the line's character rate.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "modbus_rtu_driver/core/modbus/request_framer.h"
#include "modbus_rtu_driver/sim/pty_link.h"
#include "modbus_rtu_driver/sim/sim_control_socket.h"
#include "modbus_rtu_driver/sim/sim_device.h"
#include "modbus_rtu_driver/sim/sim_gateway.h"
#include "modbus_rtu_driver/sim/sim_generic.h"
#include "modbus_rtu_driver/sim/simulator_config.h"

namespace modbus_rtu_driver {

// What the line carries when several devices answer at once: garbled bytes, never a valid frame.
Bytes collideReplies(const std::vector<Bytes>& replies);

struct SimulatorOptions {
  std::string link;        // path of the symlink to the pty's slave side
  std::string control;     // Unix socket path; empty = link + ".ctl"
  std::string state_file;  // empty = no persistence
  bool verbose = false;    // print every frame ("rx 01 03 ...", "tx 01 03 ...") on stdout
  // Verbose lines carry CLOCK_MONOTONIC seconds of the frame's first and last byte:
  // "rx 12.345000 12.345678 01 03 ..." (reached the simulator), "tx ..." (written).
  bool timestamps = false;
  int rtu_tcp_port = -1;  // also serve the line as an RTU-over-TCP gateway; 0 = a free port
};

class Simulator {
 public:
  Simulator(SimulatorConfig config, SimulatorOptions options);
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  // Loads the state file, creates the pty, the link and the control socket, starts the thread.
  bool start(std::string* error);
  // Stops the thread; removes the link and the socket this run made (not one that belongs to
  // another simulator). Replies still waiting are lost.
  void stop();
  // One control command, as on the socket ("get 255 coil 0 8" -> "ok 0 1 ..."). Thread-safe.
  std::string command(const std::string& line);
  // Async-signal-safe: the line thread power-cycles the devices at its next turn.
  void requestPowerCycle() { power_cycle_requested_ = true; }
  const std::string& link() const { return options_.link; }
  // Whether a program (a bus node) holds the link's port open and locked; any thread.
  bool linkClaimed() const { return pty_.claimed(); }
  const std::string& controlPath() const { return options_.control; }
  // The RTU-over-TCP gateway's port on 127.0.0.1 (0 when not serving one); valid after start.
  int rtuTcpPort() const { return gateway_.port(); }

 private:
  struct Outgoing {  // a reply on its way out
    Bytes bytes;
    size_t sent = 0;
    SimClock::time_point start;
    SimClock::duration per_byte{};  // zero: all at once
    SimClock::time_point first_written{};
  };

  void run();
  SimClock::duration waitTime(SimClock::time_point now) const;
  void take(const uint8_t* data, size_t size, SimClock::time_point now);  // bytes onto the line
  void processFrame(const Bytes& frame, SimClock::time_point now);
  void broadcast(const std::optional<Request>& request, const std::vector<SimDevice*>& hearing,
                 SimClock::time_point now, SimClock::time_point request_end);
  // A frame that several devices take (see above): each does it, their replies collide.
  void collide(const std::optional<Request>& request, uint8_t slave, uint8_t function,
               const std::vector<SimDevice*>& targets, SimClock::time_point now,
               SimClock::time_point request_end);
  void send(SimDevice& device, Bytes reply, double delay, SimClock::time_point request_end);
  void flushOutgoing(SimClock::time_point now);
  bool chance(int percent);  // the drop faults; a fixed seed, so a run can be repeated
  SimDevice* find(const std::string& name);
  void powerCycle(SimClock::time_point now);
  void saveState();
  void loadState(SimClock::time_point now);
  std::string doCommand(const std::string& line);  // the line thread's, under mutex_

  SimulatorConfig config_;
  SimulatorOptions options_;
  std::vector<std::unique_ptr<SimDevice>> devices_;
  std::mutex mutex_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<bool> power_cycle_requested_{false};
  PtyLink pty_;
  SimGateway gateway_;        // the same line, reached over TCP
  SimControlSocket control_;  // the line thread's
  RequestFramer framer_;
  SimLineSettings line_;  // the line's settings when the last bytes came
  SimClock::time_point last_byte_{}, rx_start_{}, line_free_{};
  std::vector<Outgoing> outgoing_;
  std::string state_text_;  // last written to the state file
  uint64_t frames_ = 0, answered_ = 0;
  std::mt19937 random_{20261124};
};

}  // namespace modbus_rtu_driver
