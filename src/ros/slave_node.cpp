#include "modbus_rtu_driver/ros/slave_node.h"

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <std_msgs/Bool.h>
#include <std_msgs/UInt16.h>

#include "modbus_rtu_driver/WrittenCoils.h"
#include "modbus_rtu_driver/WrittenRegisters.h"
#include "modbus_rtu_driver/ros/renamed_publisher.h"
#include "modbus_rtu_driver/ros/yaml_params.h"

namespace modbus_rtu_driver {

SlaveNode::SlaveNode(const ros::NodeHandle& private_nh) : nh_(private_nh) {}

SlaveNode::~SlaveNode() {
  if (server_) server_->stop();  // its thread publishes through this object
}

// Each service under its name and under its old, plural name; the old one warns once, then
// serves the same.
template <class Request, class Response>
void SlaveNode::serve(const std::string& name,
                      const std::function<bool(Request&, Response&)>& handler) {
  const std::string resolved = nh_.resolveName(name);
  const std::string old_name = nh_.resolveName(name + "s");
  services_.push_back(nh_.advertiseService<Request, Response>(name, handler));
  services_.push_back(nh_.advertiseService<Request, Response>(
      name + "s", [handler, resolved, old_name](Request& q, Response& s) {
        warnRenamed(old_name, resolved);
        return handler(q, s);
      }));
}

bool SlaveNode::start() {
  XmlRpc::XmlRpcValue params;
  std::string error;
  if (!nh_.getParam("", params) || !parseSlaveConfig(toYaml(params), &config_, &error)) {
    ROS_FATAL("invalid configuration in %s: %s", nh_.getNamespace().c_str(), error.c_str());
    return false;
  }
  // Names follow the YAML's singular table names (coil, holding_register); the plural names
  // of earlier versions still work for one release and warn once (docs/ros_api.md).
  written_coils_ =
      RenamedPublisher::advertise<WrittenCoils>(nh_, "written/coil", "written/coils", 100);
  written_registers_ = RenamedPublisher::advertise<WrittenRegisters>(
      nh_, "written/holding_register", "written/holding_registers", 100);
  for (const auto& [address, name] : config_.coil_names) {
    coil_pubs_[address] =
        RenamedPublisher::advertise<std_msgs::Bool>(nh_, "coil/" + name, "coils/" + name, 1, true);
    publishNamed(Table::kCoil, address, {0});
  }
  for (const auto& [address, name] : config_.holding_names) {
    holding_pubs_[address] = RenamedPublisher::advertise<std_msgs::UInt16>(
        nh_, "holding_register/" + name, "holding_registers/" + name, 1, true);
    publishNamed(Table::kHoldingRegister, address, {0});
  }
  auto bits = [this](const std::string& name, Table table) {
    serve<SetBits::Request, SetBits::Response>(
        name,
        [this, table](SetBits::Request& q, SetBits::Response& s) { return setBits(table, q, s); });
  };
  auto regs = [this](const std::string& name, Table table) {
    serve<SetRegisters::Request, SetRegisters::Response>(
        name, [this, table](SetRegisters::Request& q, SetRegisters::Response& s) {
          return setRegisters(table, q, s);
        });
  };
  bits("set_coil", Table::kCoil);
  bits("set_discrete_input", Table::kDiscreteInput);
  regs("set_holding_register", Table::kHoldingRegister);
  regs("set_input_register", Table::kInputRegister);

  diagnostics_ = std::make_unique<diagnostic_updater::Updater>();
  diagnostics_->setHardwareID(config_.link.port);
  diagnostics_->add("slave " + std::to_string(config_.slave_id) + " on " + config_.link.port, this,
                    &SlaveNode::diagnose);
  diagnostics_timer_ =
      nh_.createTimer(ros::Duration(config_.diagnostic_period),
                      [this](const ros::TimerEvent&) { diagnostics_->force_update(); });

  server_ = std::make_unique<SlaveServer>(config_, [this](const SlaveWrite& w) { onWrite(w); });
  server_->start();
  ROS_INFO("slave %d on %s at %d baud", config_.slave_id, config_.link.port.c_str(),
           config_.link.baud);
  return true;
}

void SlaveNode::onWrite(const SlaveWrite& w) {
  const ros::Time now = ros::Time::now();
  if (w.table == Table::kCoil) {
    WrittenCoils msg;
    msg.header.stamp = now;
    msg.address = w.address;
    msg.states.assign(w.values.begin(), w.values.end());
    written_coils_.publish(std::move(msg));
  } else {
    WrittenRegisters msg;
    msg.header.stamp = now;
    msg.address = w.address;
    msg.values = w.values;
    msg.bytes = registersToMacroBytes(w.values);
    written_registers_.publish(std::move(msg));
  }
  publishNamed(w.table, w.address, w.values);
}

// Named signals: published on change (and once at start, latched).
void SlaveNode::publishNamed(Table table, uint16_t address, const std::vector<uint16_t>& values) {
  auto& pubs = table == Table::kCoil ? coil_pubs_ : holding_pubs_;
  if (table != Table::kCoil && table != Table::kHoldingRegister) return;
  std::lock_guard<std::mutex> lock(named_mutex_);
  for (size_t i = 0; i < values.size(); ++i) {
    const auto a = static_cast<uint16_t>(address + i);
    auto pub = pubs.find(a);
    if (pub == pubs.end()) continue;
    const auto key = std::make_pair(static_cast<int>(table), a);
    auto last = named_values_.find(key);
    if (last != named_values_.end() && last->second == values[i]) continue;
    named_values_[key] = values[i];
    if (table == Table::kCoil) {
      std_msgs::Bool b;
      b.data = values[i] != 0;
      pub->second.publish(b);
    } else {
      std_msgs::UInt16 u;
      u.data = values[i];
      pub->second.publish(u);
    }
  }
}

bool SlaveNode::setBits(Table table, SetBits::Request& req, SetBits::Response& res) {
  const std::vector<uint16_t> values(req.values.begin(), req.values.end());
  res.message = server_->set(table, req.address, values);
  res.success = res.message.empty();
  if (res.success) {
    publishNamed(table, req.address, values);
    res.message = tableName(table) + (" " + std::to_string(req.address)) + ": " +
                  std::to_string(values.size()) + " value(s) set";
  }
  return true;
}

bool SlaveNode::setRegisters(Table table, SetRegisters::Request& req, SetRegisters::Response& res) {
  res.message = server_->set(table, req.address, req.values);
  res.success = res.message.empty();
  if (res.success) {
    publishNamed(table, req.address, req.values);
    res.message = tableName(table) + (" " + std::to_string(req.address)) + ": " +
                  std::to_string(req.values.size()) + " value(s) set";
  }
  return true;
}

void SlaveNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  using diagnostic_msgs::DiagnosticStatus;
  const SlaveStats s = server_->stats();
  if (!s.port_open) {
    status.summary(DiagnosticStatus::ERROR, "port not open: " + s.port_error);
  } else if (s.since_last_heard < 0) {
    status.summary(DiagnosticStatus::WARN, "no request from the master yet");
  } else if (s.crc_errors > 0) {
    status.summary(DiagnosticStatus::WARN, "serving; CRC errors seen");
  } else {
    status.summary(DiagnosticStatus::OK, "serving");
  }
  status.add("slave id", config_.slave_id);
  status.add("requests served", s.requests_served);
  status.add("exceptions sent", s.exceptions_sent);
  status.add("broadcasts", s.broadcasts);
  status.add("crc errors", s.crc_errors);
  status.add("frames for other ids", s.other_slave);
  status.add("exception replies heard (ignored)", s.not_requests);
  status.add("since master last heard [s]", s.since_last_heard);
}

}  // namespace modbus_rtu_driver
