// The configuration of one bus node (what the YAML in the node's private namespace says),
// checked key by key. It sits above the devices (it checks each device against its type) and
// below the ROS node, which converts its parameters to a YAML::Node and calls parseBusConfig.
#pragma once

#include <string>
#include <vector>

#include "modbus_rtu_driver/core/config/link_config.h"
#include "modbus_rtu_driver/core/config/share_config.h"
#include "modbus_rtu_driver/core/link/link_types.h"
#include "modbus_rtu_driver/devices/device.h"

namespace YAML {
class Node;
}

namespace modbus_rtu_driver {

// roslaunch sends SIGTERM 15 s after SIGINT and SIGKILL 2 s later: the safe writes at stop
// (at most this) plus the bus thread's last transaction (BusNode::kBusStopGrace) fit before.
constexpr double kMaxShutdownTimeout = 10.0;  // s

struct BusConfig {
  LinkConfig link;
  LinkTarget link_target;          // link.port, parsed (makeLink takes it)
  std::string role = "master";     // master: the node polls devices; slave: a master polls the node
  double diagnostic_period = 1.0;  // s
  // State topics (outputs, inputs): false = an array message every poll; true = only when a
  // state changes, and at least every `keep_alive` s (smaller bags: about 6.5 KB/s in the demo
  // otherwise).
  bool publish_on_change = false;
  double keep_alive = 1.0;  // s, 0.1-3600
  // The write_registers / write_coils services reach any register of any slave, settings such as
  // address and baud included: refused unless the configuration says so.
  bool allow_raw_writes = false;
  // Fail-safe: a heartbeat for the whole bus (any message type on `heartbeat_topic`; none within
  // `heartbeat_timeout` s puts every channel with a safe state there), and how long the node may
  // spend writing safe states when it shuts down.
  std::string heartbeat_topic;
  double heartbeat_timeout = 0.0;
  double shutdown_timeout = 3.0;  // s, 0-kMaxShutdownTimeout
  // The bus thread's SCHED_FIFO priority, 1-99; 0 = the normal scheduler. And whether the node
  // locks its memory (mlockall). Both need the user's limits to allow them (docs/ros_api.md).
  int realtime_priority = 0;
  bool lock_memory = false;
  // A file the node writes every frame to, with when it was sent or read and the bus thread's
  // CPU time (formatWireEvent, core/link/link.h); empty = none.
  std::string wire_log;
  // `share`: Modbus TCP clients reach the bus through the node (docs/share.md); off unless set.
  ShareConfig share;
  std::vector<DeviceConfig> devices;
  // Words of an older release the YAML used, each "KEY: 'OLD' is deprecated, use 'NEW'": still
  // taken; the node warns of each at start (docs/releases.md).
  std::vector<std::string> deprecated;
};

// False with one message naming the key, the value and what is allowed; `out` is then undefined.
bool parseBusConfig(const YAML::Node& root, BusConfig* out, std::string* error);

// Every key either role accepts ("devices/D/type" for device keys), for documentation checks.
std::vector<std::string> configKeys();

}  // namespace modbus_rtu_driver
