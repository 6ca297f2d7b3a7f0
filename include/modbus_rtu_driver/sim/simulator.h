// The simulated RS485 line: a pseudo-terminal whose slave side is linked at a path the driver
// opens like a serial port, several SimDevices on it, a control socket for tests, a power cycle
// and a state file. One thread does everything, so devices need no locks of their own; the
// in-process API (command) takes the same mutex.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "modbus_rtu_driver/core/request_framer.h"
#include "modbus_rtu_driver/sim/pty_link.h"
#include "modbus_rtu_driver/sim/sim_device.h"

namespace modbus_rtu_driver {

struct SimulatorConfig {
  SimLineSettings factory;  // what the devices start at
  bool pace = false;        // give frames their real wire time
  struct Entry {
    std::string type;
    int address;
  };
  std::vector<Entry> devices;
};

// False with a message naming the key when the YAML does not fit.
bool loadSimulatorConfig(const std::string& path, SimulatorConfig* out, std::string* error);

struct SimulatorOptions {
  std::string link;        // path of the symlink to the pty's slave side
  std::string control;     // Unix socket path; empty = link + ".ctl"
  std::string state_file;  // empty = no persistence
  bool verbose = false;    // print every frame
};

class Simulator {
 public:
  Simulator(SimulatorConfig config, SimulatorOptions options);
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  bool start(std::string* error);
  void stop();
  // One control command, as on the socket ("get 255 coil 0 8" -> "ok 0 1 ..."). Thread-safe.
  std::string command(const std::string& line);
  void requestPowerCycle() { power_cycle_requested_ = true; }
  const std::string& link() const { return options_.link; }

 private:
  void run();
  void processFrame(const Bytes& frame);
  void answer(SimDevice& device, const Bytes& request, const Bytes& reply, double delay);
  SimLineSettings lineSettings() const;
  SimDevice* find(const std::string& name);
  void powerCycle();
  void saveState();
  void loadState();
  void serveControl();
  std::string doCommand(const std::string& line);

  SimulatorConfig config_;
  SimulatorOptions options_;
  std::vector<std::unique_ptr<SimDevice>> devices_;
  std::mutex mutex_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<bool> power_cycle_requested_{false};
  PtyLink pty_;
  int listen_fd_ = -1;
  std::vector<int> clients_;
  std::vector<std::string> client_buffers_;
  RequestFramer framer_;
  SimClock::time_point last_byte_{}, busy_until_{};
  uint64_t frames_ = 0, answered_ = 0, bad_crc_ = 0;
};

}  // namespace modbus_rtu_driver
