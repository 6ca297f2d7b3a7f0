#include "modbus_rtu_driver/ros/share_bridge.h"

#include <diagnostic_msgs/DiagnosticStatus.h>

#include <utility>

namespace modbus_rtu_driver {

ShareBridge::ShareBridge(ShareGateway& gateway, ShareConfig config)
    : gateway_(gateway), config_(std::move(config)) {}

// Errors name the key to change: a second bus left on the default listen address (1502) is the
// usual cause of a taken port (docs/share.md, "Several buses").
namespace {
std::string startError(const ShareConfig& config, bool in_use, const std::string& why) {
  return in_use ? "share/listen: " + config.server.host + ":" + std::to_string(config.server.port) +
                      ": address in use (another bus's share, or another program, listens "
                      "there): give each bus its own share/listen port"
                : "share: " + why;
}
}  // namespace

bool ShareBridge::start(std::string* error) {
  std::string why;
  if (gateway_.start(&why)) return true;
  if (error) *error = startError(config_, gateway_.server().addressInUse(), why);
  return false;
}

bool ShareBridge::canStart(const ShareConfig& config, std::string* error) {
  if (config.server.port == 0) return true;  // any free port
  std::string why;
  bool in_use = false;
  if (ModbusTcpServer::canListen(config.server.host, config.server.port, &why, &in_use))
    return true;
  if (error) *error = startError(config, in_use, why);
  return false;
}

void ShareBridge::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  using diagnostic_msgs::DiagnosticStatus;
  const ModbusTcpServer::Stats s = gateway_.server().stats();
  const std::string where = config_.server.host + ":" + std::to_string(gateway_.server().port());
  status.summary(DiagnosticStatus::OK,
                 "Modbus TCP on " + where + ", " + std::to_string(s.connected) + " client(s)");
  status.add("listen", where);
  status.add("read only", config_.read_only ? "yes" : "no");
  status.add("clients", s.connected);
  status.add("max clients", config_.server.max_clients);
  status.add("queued", gateway_.queued());
  status.add("max queue", config_.max_queue);
  status.add("answer bound [s]", gateway_.answerBound());
  status.add("answered 0B at the bound (unsent)", gateway_.expired());
  status.add("shared requests run in a guard", gateway_.ranInGuards());
  status.add("shared reads retried after a guard", gateway_.cutInGuards());
  status.add("accepted", s.accepted);
  status.add("refused (not allowed)", s.refused_not_allowed);
  status.add("refused (too many clients)", s.refused_too_many);
  status.add("closed (malformed)", s.malformed);
  status.add("closed (idle)", s.idle_closed);
  status.add("half-closed by the client", s.half_closed);
  status.add("idle timeout [s]", config_.server.idle_timeout);
  for (const auto& [peer, counts] : s.peers) {
    status.add("requests from " + peer, counts.requests);
    status.add("exceptions to " + peer, counts.exceptions);
    status.add("connections from " + peer, counts.connections);
  }
}

}  // namespace modbus_rtu_driver
