#include "modbus_rtu_driver/sim/simulator_tcp.h"

namespace modbus_rtu_driver {

SimulatorTcp::SimulatorTcp(const SimulatorConfig& config, const std::string& link) {
  LinkConfig line;
  line.port = link;
  line.baud = config.factory.baud;
  line.parity = config.factory.parity;
  line.stop_bits = config.factory.stop_bits;
  line.response_timeout = 0.5;
  link_ = makeLink(line);  // the pty: a serial link, by its path
  scheduler_ = std::make_unique<BusScheduler>(*link_);
}

SimulatorTcp::~SimulatorTcp() {
  stop();
}

bool SimulatorTcp::start(const std::string& listen, std::string* error) {
  ShareConfig share;
  share.enabled = true;
  share.server.allow = {"0.0.0.0/0"};
  share.server.max_clients = 16;
  if (!parseListenAddress(listen, &share.server.host, &share.server.port, error)) return false;
  std::string why;
  if (!link_->connect(&why)) {  // now, so a pty that cannot be opened is an error at start
    if (error) *error = "cannot open the line " + link_->config().port + ": " + why;
    return false;
  }
  gateway_ = std::make_unique<ShareGateway>(*scheduler_, share);
  scheduler_->start();
  return gateway_->start(error);
}

void SimulatorTcp::stop() {
  if (gateway_) gateway_->stop();
  scheduler_->stop();  // before the gateway goes: pending answers call into it
  gateway_.reset();
  link_->disconnect();
}

void SimulatorTcp::dropClients() {
  if (gateway_) gateway_->server().dropClients();
}

uint16_t SimulatorTcp::port() const {
  return gateway_ ? gateway_->server().port() : 0;
}

}  // namespace modbus_rtu_driver
