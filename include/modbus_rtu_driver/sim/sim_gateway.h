// The simulator's transparent RS485-Ethernet gateway: a TCP listener on 127.0.0.1 whose
// connections carry RTU frames. What a connection sends goes onto the simulated line (the same
// framing and devices as the pty); what the line carries goes to every connection, as a
// transparent gateway forwards it. It can drop its connections and stay down a while, as a
// gateway that reboots. Used by the simulator's thread only.
#pragma once

#include <poll.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/modbus/frame.h"

namespace modbus_rtu_driver {

class SimGateway {
 public:
  using Clock = std::chrono::steady_clock;
  SimGateway() = default;
  ~SimGateway() { close(); }
  SimGateway(const SimGateway&) = delete;
  SimGateway& operator=(const SimGateway&) = delete;

  // Listens on 127.0.0.1:port (0 = a free port, see port()). False with a message.
  bool listen(int port, std::string* error);
  void close();
  bool enabled() const { return port_ > 0; }
  int port() const { return port_; }
  void addPollFds(std::vector<pollfd>* fds) const;
  // Accepts new connections (once back up) and appends what they sent to `in`; false when none
  // sent anything.
  bool receive(Clock::time_point now, Bytes* in);
  // The line's bytes to every connection; one that cannot take them is closed.
  void send(const uint8_t* data, size_t size);
  // Closes every connection; with down_seconds > 0 it also refuses new ones that long.
  void drop(double down_seconds, Clock::time_point now);
  // "port P connections N accepted N dropped N"
  std::string status() const;

 private:
  bool openListener(std::string* error);

  int port_ = 0;
  int listen_fd_ = -1;
  std::vector<int> connections_;
  Clock::time_point down_until_{};
  uint64_t accepted_ = 0, dropped_ = 0;
};

}  // namespace modbus_rtu_driver
