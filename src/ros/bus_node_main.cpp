// modbus_rtu_bus: one node per serial bus. Configuration: YAML in the private namespace;
// `role: master` (default) polls devices, `role: slave` serves a Modbus master.
#include <ros/ros.h>

#include <csignal>
#include <cstdio>

#include "modbus_rtu_driver/ros/bus_node.h"
#include "modbus_rtu_driver/ros/slave_node.h"

template <typename Node>
int run(const ros::NodeHandle& nh) {
  Node node(nh);
  if (!node.start()) return 1;
  // Service callbacks wait for the bus; several threads keep callers from queueing on each other.
  ros::AsyncSpinner spinner(modbus_rtu_driver::BusNode::kServiceThreads);
  spinner.start();
  ros::waitForShutdown();
  spinner.stop();
  node.shutdown();  // the fail-safe's shutdown writes, then the port closes
  return 0;
}

int main(int argc, char** argv) {
  // rosconsole writes INFO to stdout: line-buffered, so "back online" reaches a log file when
  // it happens, not at exit, when roslaunch's output goes to a file.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  ros::init(argc, argv, "modbus_rtu_bus");
  // roscpp handles SIGINT; SIGTERM (systemd, docker stop, kill) must end as cleanly.
  std::signal(SIGTERM, [](int) { ros::requestShutdown(); });
  ros::NodeHandle nh("~");
  const std::string role = nh.param<std::string>("role", "master");
  if (role == "slave") return run<modbus_rtu_driver::SlaveNode>(nh);
  return run<modbus_rtu_driver::BusNode>(nh);
}
