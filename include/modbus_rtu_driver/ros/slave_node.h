// The slave role of the bus node: serves a Modbus master (such as the DM500 controller) and
// gives ROS what it writes, and sets what it reads.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>

#include <functional>
#include <map>
#include <memory>
#include <mutex>

#include "modbus_rtu_driver/SetBits.h"
#include "modbus_rtu_driver/SetRegisters.h"
#include "modbus_rtu_driver/core/server/slave_server.h"
#include "modbus_rtu_driver/ros/renamed_publisher.h"

namespace modbus_rtu_driver {

class SlaveNode {
 public:
  explicit SlaveNode(const ros::NodeHandle& private_nh);
  ~SlaveNode();
  bool start();       // false (logged) when the configuration is invalid
  void shutdown() {}  // nothing to put in a safe state: the master owns the outputs

 private:
  template <class Request, class Response>
  void serve(const std::string& name, const std::function<bool(Request&, Response&)>& handler);
  void onWrite(const SlaveWrite& write);  // server thread
  void publishNamed(Table table, uint16_t address, const std::vector<uint16_t>& values);
  bool setBits(Table table, SetBits::Request& req, SetBits::Response& res);
  bool setRegisters(Table table, SetRegisters::Request& req, SetRegisters::Response& res);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  ros::NodeHandle nh_;
  SlaveConfig config_;
  std::unique_ptr<SlaveServer> server_;
  RenamedPublisher written_coils_, written_registers_;
  std::map<uint16_t, RenamedPublisher> coil_pubs_, holding_pubs_;
  std::mutex named_mutex_;
  std::map<std::pair<int, uint16_t>, uint16_t> named_values_;  // (table, address) -> last
  std::vector<ros::ServiceServer> services_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::Timer diagnostics_timer_;
};

}  // namespace modbus_rtu_driver
