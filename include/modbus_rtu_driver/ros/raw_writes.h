// The bus node's raw write services, ~write_registers (FC16) and ~write_coils (FC15): any
// register of any slave, device settings such as address and baud included, so they answer
// "refused" unless the configuration sets allow_raw_writes. Checked before anything is queued;
// run on the bus thread like every other request.
#pragma once

#include <ros/ros.h>

#include <functional>
#include <map>
#include <string>

#include "modbus_rtu_driver/WriteCoils.h"
#include "modbus_rtu_driver/WriteRegisters.h"
#include "modbus_rtu_driver/core/bus/bus_scheduler.h"

namespace modbus_rtu_driver {

class RawWrites {
 public:
  // `devices`: address -> device name of the configured devices (their health applies).
  // `wrote(request, result)`: on the bus thread, a raw write went out, with its outcome.
  RawWrites(ros::NodeHandle& nh, BusScheduler& scheduler, bool allowed,
            std::map<uint8_t, std::string> devices,
            std::function<void(const Request&, const Result&)> wrote);

 private:
  bool onRegisters(WriteRegisters::Request& req, WriteRegisters::Response& res);
  bool onCoils(WriteCoils::Request& req, WriteCoils::Response& res);
  // Why a write of `count` values may not go out (empty: it may).
  std::string refusal(uint8_t slave, uint16_t address, size_t count, size_t max) const;
  Result run(const Request& request);

  BusScheduler& scheduler_;
  bool allowed_;
  std::map<uint8_t, std::string> devices_;
  std::function<void(const Request&, const Result&)> wrote_;
  ros::ServiceServer registers_srv_, coils_srv_;
};

}  // namespace modbus_rtu_driver
