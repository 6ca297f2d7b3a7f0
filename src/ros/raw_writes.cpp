#include "modbus_rtu_driver/ros/raw_writes.h"

namespace modbus_rtu_driver {

RawWrites::RawWrites(ros::NodeHandle& nh, BusRuntime& runtime) : runtime_(runtime) {
  registers_srv_ = nh.advertiseService("write_registers", &RawWrites::onRegisters, this);
  coils_srv_ = nh.advertiseService("write_coils", &RawWrites::onCoils, this);
}

std::string RawWrites::refusal(uint8_t slave, uint16_t address, size_t count, size_t max) const {
  std::string refused = runtime_.rawWriteRefusal(slave);  // off, or a broadcast
  if (!refused.empty()) return refused;
  if (count < 1 || count > max)
    return "values: " + std::to_string(count) + " given, 1-" + std::to_string(max) + " allowed";
  if (address + count > 0x10000)
    return "address: " + std::to_string(address) + " + " + std::to_string(count) +
           " values run past 65535";
  return {};
}

bool RawWrites::onRegisters(WriteRegisters::Request& req, WriteRegisters::Response& res) {
  const std::vector<uint16_t> values(req.values.begin(), req.values.end());
  const std::string no = refusal(req.slave, req.address, values.size(), kMaxWriteRegisters);
  const Result r =
      no.empty()
          ? runtime_.rawWrite(Request::writeMultipleRegisters(req.slave, req.address, values)).get()
          : Result::failure(ErrorKind::kInvalidArgument, no);
  res.success = r.ok();
  res.message = r.ok() ? std::to_string(values.size()) + " register(s) written" : r.message;
  return true;
}

bool RawWrites::onCoils(WriteCoils::Request& req, WriteCoils::Response& res) {
  const std::vector<bool> values(req.values.begin(), req.values.end());
  const std::string no = refusal(req.slave, req.address, values.size(), kMaxWriteBits);
  const Result r =
      no.empty()
          ? runtime_.rawWrite(Request::writeMultipleCoils(req.slave, req.address, values)).get()
          : Result::failure(ErrorKind::kInvalidArgument, no);
  res.success = r.ok();
  res.message = r.ok() ? std::to_string(values.size()) + " coil(s) written" : r.message;
  return true;
}

}  // namespace modbus_rtu_driver
