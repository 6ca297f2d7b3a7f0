// The node's share (`share` in the bus YAML): a ShareGateway on the node's bus thread, and its
// /diagnostics entry (clients, refusals, requests per client address). See docs/share.md.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>

#include <functional>
#include <memory>
#include <string>

#include "modbus_rtu_driver/core/server/share_gateway.h"
#include "modbus_rtu_driver/node_config/bus_config.h"

namespace modbus_rtu_driver {

class ShareBridge {
 public:
  // `wrote(request, result)`: on the bus thread, a client's write went out, with its outcome.
  // `transaction_time`: the link's longest transaction for a request (the answer bound's).
  ShareBridge(BusScheduler& scheduler, const BusConfig& config,
              std::function<void(const Request&, const Result&)> wrote,
              ShareGateway::TransactionTime transaction_time);
  // s: every request is answered within this (docs/share.md); valid after start().
  double answerBound() const { return gateway_->answerBound(); }
  // Listens; false with the reason, naming the key to change (share/listen when the address is
  // in use).
  bool start(std::string* error);
  // Before the bus is touched: false, with start()'s message, when the share could not listen
  // now (another bus's share on the port), so that a node that will stop writes nothing first.
  static bool canStart(const ShareConfig& config, std::string* error);
  void stop();
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  const ShareConfig& config() const { return config_; }

 private:
  ShareConfig config_;
  std::unique_ptr<ShareGateway> gateway_;
};

}  // namespace modbus_rtu_driver
