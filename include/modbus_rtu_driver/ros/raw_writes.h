// The bus node's raw write services, ~write_registers (FC16) and ~write_coils (FC15): any
// register of any slave, device settings such as address and baud included, so they answer
// "refused" unless the configuration sets allow_raw_writes. Checked before anything is queued;
// the bus runtime sends them (BusRuntime::rawWrite).
#pragma once

#include <ros/ros.h>

#include <string>

#include "modbus_rtu_driver/WriteCoils.h"
#include "modbus_rtu_driver/WriteRegisters.h"
#include "modbus_rtu_driver/runtime/bus_runtime.h"

namespace modbus_rtu_driver {

class RawWrites {
 public:
  RawWrites(ros::NodeHandle& nh, BusRuntime& runtime);

 private:
  bool onRegisters(WriteRegisters::Request& req, WriteRegisters::Response& res);
  bool onCoils(WriteCoils::Request& req, WriteCoils::Response& res);
  // Why a write of `count` values may not go out (empty: it may).
  std::string refusal(uint8_t slave, uint16_t address, size_t count, size_t max) const;

  BusRuntime& runtime_;
  ros::ServiceServer registers_srv_, coils_srv_;
};

}  // namespace modbus_rtu_driver
