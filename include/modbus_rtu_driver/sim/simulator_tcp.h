// The simulator's devices over Modbus TCP (`--tcp HOST:PORT`): a gateway in front of the
// simulated line, as a Modbus TCP/RTU gateway stands in front of an RS485 bus. It opens the
// pty as any master does (makeLink: an RtuLink at the devices' factory line settings, 0.5 s
// response timeout) and serves it with the node's share code (ShareGateway: a bus thread, the
// ModbusTcpServer). While it runs the line is its own (the port is claimed): clients reach the
// devices through TCP only. Everyone may connect (a simulator: `allow` is 0.0.0.0/0).
#pragma once

#include <memory>
#include <string>

#include "modbus_rtu_driver/core/bus/bus_scheduler.h"
#include "modbus_rtu_driver/core/link/make_link.h"
#include "modbus_rtu_driver/core/server/share_gateway.h"
#include "modbus_rtu_driver/sim/simulator.h"

namespace modbus_rtu_driver {

class SimulatorTcp {
 public:
  // `listen` is HOST:PORT (an IPv4 host); `link` the simulator's pty link.
  SimulatorTcp(const SimulatorConfig& config, const std::string& link);
  ~SimulatorTcp();
  // False with a message (bad address, port in use, the pty cannot be opened).
  bool start(const std::string& listen, std::string* error);
  void stop();
  // Every client connection closes (a gateway reboot); new ones are taken.
  void dropClients();
  uint16_t port() const;

 private:
  std::unique_ptr<Link> link_;
  std::unique_ptr<BusScheduler> scheduler_;
  std::unique_ptr<ShareGateway> gateway_;
};

}  // namespace modbus_rtu_driver
