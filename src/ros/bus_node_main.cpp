// modbus_rtu_bus: one node per serial bus. Configuration: YAML in the private namespace.
#include <ros/ros.h>

#include "modbus_rtu_driver/ros/bus_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "modbus_rtu_bus");
  modbus_rtu_driver::BusNode node(ros::NodeHandle("~"));
  if (!node.start()) return 1;
  // Service callbacks wait for the bus; several threads keep callers from queueing on each other.
  ros::AsyncSpinner spinner(4);
  spinner.start();
  ros::waitForShutdown();
  return 0;
}
