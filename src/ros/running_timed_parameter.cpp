#include "modbus_rtu_driver/ros/running_timed_parameter.h"

#include <pthread.h>
#include <ros/time.h>

#include <utility>

namespace modbus_rtu_driver {

double RunningTimedParameter::seconds() const {
  return ros::WallTime::now().toSec();
}

namespace {

std::string keyOf(const std::string& device) {
  return device;
}

std::vector<KeptTimedCommand> readParameter(const ros::NodeHandle& node,
                                            const std::string& device) {
  std::vector<KeptTimedCommand> kept;
  XmlRpc::XmlRpcValue list;
  if (!node.getParam(keyOf(device), list) || list.getType() != XmlRpc::XmlRpcValue::TypeArray)
    return kept;
  for (int i = 0; i < list.size(); ++i) {
    XmlRpc::XmlRpcValue& e = list[i];
    // Not what writeParameter writes (edited by hand): skipped.
    if (e.getType() != XmlRpc::XmlRpcValue::TypeStruct || !e.hasMember("channel") ||
        !e.hasMember("after") || !e.hasMember("during") || !e.hasMember("ends") ||
        e["channel"].getType() != XmlRpc::XmlRpcValue::TypeInt ||
        e["during"].getType() != XmlRpc::XmlRpcValue::TypeInt ||
        e["after"].getType() != XmlRpc::XmlRpcValue::TypeBoolean ||
        e["ends"].getType() != XmlRpc::XmlRpcValue::TypeDouble)
      continue;
    const int channel = static_cast<int>(e["channel"]);
    if (channel < 0 || channel > 255) continue;
    KeptTimedCommand k;
    k.channel = static_cast<uint8_t>(channel);
    k.during = static_cast<int>(e["during"]);
    k.after = static_cast<bool>(e["after"]);
    k.ends = static_cast<double>(e["ends"]);
    kept.push_back(k);
  }
  return kept;
}

void writeParameter(const ros::NodeHandle& node, const std::string& device,
                    const std::vector<KeptTimedCommand>& kept) {
  if (kept.empty()) {
    node.deleteParam(keyOf(device));
    return;
  }
  XmlRpc::XmlRpcValue list;
  list.setSize(static_cast<int>(kept.size()));
  for (size_t i = 0; i < kept.size(); ++i) {
    XmlRpc::XmlRpcValue& e = list[static_cast<int>(i)];
    e["channel"] = static_cast<int>(kept[i].channel);
    e["during"] = kept[i].during;
    e["after"] = kept[i].after;
    e["ends"] = kept[i].ends;
  }
  node.setParam(keyOf(device), list);
}

}  // namespace

std::string RunningTimedParameter::namespaceOf(const std::string& node) {
  return std::string(kRunningTimedRoot) + (node.empty() || node[0] != '/' ? "/" : "") + node;
}

std::unique_ptr<RunningTimedParameter> RunningTimedParameter::onParameterServer(
    const ros::NodeHandle& private_node) {
  // Not under the node's private namespace: bus.launch's clear_params (and any launch file's)
  // deletes that when the launch is started again, which is how supervisors restart a robot.
  const ros::NodeHandle node(namespaceOf(private_node.getNamespace()));
  return std::make_unique<RunningTimedParameter>(
      [node](const std::string& device) { return readParameter(node, device); },
      [node](const std::string& device, const std::vector<KeptTimedCommand>& kept) {
        writeParameter(node, device, kept);
      });
}

RunningTimedParameter::RunningTimedParameter(Read read, Write write)
    : read_(std::move(read)), state_(std::make_shared<State>()) {
  state_->write = std::move(write);
  thread_ = std::thread([state = state_] {
    pthread_setname_np(pthread_self(), "modbus_params");
    run(state);
  });
}

RunningTimedParameter::~RunningTimedParameter() {
  bool in_write = false;
  {
    std::lock_guard<std::mutex> lock(state_->mutex);
    state_->stopping = true;
    in_write = state_->writing;
    state_->wake.notify_one();
  }
  // A write to a master that does not answer can last until roscpp's shutdown or TCP's timeout:
  // nothing waits for it (the thread holds its own share of the state).
  if (in_write)
    thread_.detach();
  else
    thread_.join();
}

void RunningTimedParameter::keep(const std::string& device, std::vector<KeptTimedCommand> kept) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->pending[device] = std::move(kept);
  state_->wake.notify_one();
}

bool RunningTimedParameter::flush(std::chrono::steady_clock::time_point deadline) {
  std::unique_lock<std::mutex> lock(state_->mutex);
  return state_->written.wait_until(lock, deadline,
                                    [this] { return state_->pending.empty() && !state_->writing; });
}

void RunningTimedParameter::run(const std::shared_ptr<State>& state) {
  std::unique_lock<std::mutex> lock(state->mutex);
  for (;;) {
    state->wake.wait(lock, [&] { return state->stopping || !state->pending.empty(); });
    if (state->stopping) return;  // what is not written yet is flush()'s to wait for
    auto first = state->pending.begin();
    const std::string device = first->first;
    const std::vector<KeptTimedCommand> kept = std::move(first->second);
    state->pending.erase(first);
    state->writing = true;
    lock.unlock();
    state->write(device, kept);
    lock.lock();
    state->writing = false;
    if (state->pending.empty()) state->written.notify_all();
  }
}

}  // namespace modbus_rtu_driver
