// The node's share (`share` in the bus YAML): the bus runtime's ShareGateway listening, and its
// /diagnostics entry (clients, refusals, requests per client address). See docs/share.md.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>

#include <functional>
#include <memory>
#include <string>

#include "modbus_rtu_driver/core/config/share_config.h"
#include "modbus_rtu_driver/core/server/share_gateway.h"

namespace modbus_rtu_driver {

class ShareBridge {
 public:
  // `gateway`: the runtime's (BusRuntime::share), which outlives the bridge's use of it.
  ShareBridge(ShareGateway& gateway, ShareConfig config);
  // s: every request is answered within this (docs/share.md); valid after start().
  double answerBound() const { return gateway_.answerBound(); }
  // Listens; false with the reason, naming the key to change (share/listen when the address is
  // in use).
  bool start(std::string* error);
  // Before the bus is touched: false, with start()'s message, when the share could not listen
  // now (another bus's share on the port), so that a node that will stop writes nothing first.
  static bool canStart(const ShareConfig& config, std::string* error);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  const ShareConfig& config() const { return config_; }

 private:
  ShareGateway& gateway_;
  ShareConfig config_;
};

}  // namespace modbus_rtu_driver
