#include "modbus_rtu_driver/ros/raw_writes.h"

namespace modbus_rtu_driver {

RawWrites::RawWrites(ros::NodeHandle& nh, BusScheduler& scheduler, bool allowed,
                     std::map<uint8_t, std::string> devices,
                     std::function<void(const Request&, const Result&)> wrote)
    : scheduler_(scheduler),
      allowed_(allowed),
      devices_(std::move(devices)),
      wrote_(std::move(wrote)) {
  registers_srv_ = nh.advertiseService("write_registers", &RawWrites::onRegisters, this);
  coils_srv_ = nh.advertiseService("write_coils", &RawWrites::onCoils, this);
}

std::string RawWrites::refusal(uint8_t slave, uint16_t address, size_t count, size_t max) const {
  if (!allowed_)
    return "raw writes are off: set allow_raw_writes: true in the bus configuration to use them "
           "(they can change any device setting)";
  if (slave == kBroadcastAddress)
    return "slave: 0 (broadcast) is outside 1-255: a broadcast is never confirmed";
  if (count < 1 || count > max)
    return "values: " + std::to_string(count) + " given, 1-" + std::to_string(max) + " allowed";
  if (address + count > 0x10000)
    return "address: " + std::to_string(address) + " + " + std::to_string(count) +
           " values run past 65535";
  return {};
}

Result RawWrites::run(const Request& request) {
  const std::string problem = request.validate();
  if (!problem.empty()) return Result::failure(ErrorKind::kInvalidArgument, problem);
  const auto known = devices_.find(request.slave);
  const std::string owner =
      known != devices_.end() ? known->second : "slave " + std::to_string(request.slave);
  return scheduler_
      .submit(owner,
              [this, sent = forwarded(request)](Transport& t) {
                // Sent once: a raw write may start something (an LC flash through FC16).
                Result r = t.execute(sent);
                if (wrote_) wrote_(sent, r);
                return r;
              })
      .get();
}

bool RawWrites::onRegisters(WriteRegisters::Request& req, WriteRegisters::Response& res) {
  const std::vector<uint16_t> values(req.values.begin(), req.values.end());
  const std::string no = refusal(req.slave, req.address, values.size(), kMaxWriteRegisters);
  const Result r = no.empty() ? run(Request::writeMultipleRegisters(req.slave, req.address, values))
                              : Result::failure(ErrorKind::kInvalidArgument, no);
  res.success = r.ok();
  res.message = r.ok() ? std::to_string(values.size()) + " register(s) written" : r.message;
  return true;
}

bool RawWrites::onCoils(WriteCoils::Request& req, WriteCoils::Response& res) {
  const std::vector<bool> values(req.values.begin(), req.values.end());
  const std::string no = refusal(req.slave, req.address, values.size(), kMaxWriteBits);
  const Result r = no.empty() ? run(Request::writeMultipleCoils(req.slave, req.address, values))
                              : Result::failure(ErrorKind::kInvalidArgument, no);
  res.success = r.ok();
  res.message = r.ok() ? std::to_string(values.size()) + " coil(s) written" : r.message;
  return true;
}

}  // namespace modbus_rtu_driver
