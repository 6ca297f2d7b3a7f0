// The running timed commands (flashes, bursts, PWM runs) a node keeps on the parameter server as
// /modbus_rtu_driver/running_timed/<node>/<device>, for the next node under the same roscore
// (docs/failsafe.md, "What the node cannot do"). Written on a thread of its own: a parameter write
// is an XML-RPC call that roscpp retries until the master answers, and the bus thread, where timed
// commands change, must not wait for a master that is gone. Only a device's newest list is written;
// the shutdown flushes what its safe writes changed (after ROS's shutdown roscpp tries each call
// once).
#pragma once

#include <ros/node_handle.h>

#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "modbus_rtu_driver/runtime/kept_timed_store.h"

namespace modbus_rtu_driver {

class RunningTimedParameter : public KeptTimedStore {
 public:
  using Read = std::function<std::vector<KeptTimedCommand>(const std::string& device)>;
  using Write =
      std::function<void(const std::string& device, const std::vector<KeptTimedCommand>& kept)>;
  // The node's: /modbus_rtu_driver/running_timed/<node>/<device>, `private_node` the bus node's
  // private handle (its namespace is the node's full name). Outside the node's own namespace, so
  // that a launch file's clear_params, run again after the node died, does not delete it.
  static std::unique_ptr<RunningTimedParameter> onParameterServer(
      const ros::NodeHandle& private_node);
  // "/modbus_rtu_driver/running_timed/robot/io_bus" for the node "/robot/io_bus".
  static std::string namespaceOf(const std::string& node);
  static constexpr const char* kRunningTimedRoot = "/modbus_rtu_driver/running_timed";
  // Where the lists come from and go to (tests: a write that blocks as a master can).
  RunningTimedParameter(Read read, Write write);
  // Ends the thread; one still in a write is left to the process's exit.
  ~RunningTimedParameter() override;
  RunningTimedParameter(const RunningTimedParameter&) = delete;
  RunningTimedParameter& operator=(const RunningTimedParameter&) = delete;

  // What the previous node kept for `device`.
  std::vector<KeptTimedCommand> read(const std::string& device) const override {
    return read_(device);
  }
  // Any thread, without waiting: `device`'s running timed commands are now `kept` (none: the
  // key is deleted). Only the newest list not yet written is written.
  void keep(const std::string& device, std::vector<KeptTimedCommand> kept) override;
  // Wall-clock time: the list outlives the node.
  double seconds() const override;
  // Waits until every list kept so far is written, or `deadline`: false when it passed.
  bool flush(std::chrono::steady_clock::time_point deadline);

 private:
  // Shared with the thread, which may outlive this object in a write to a master that is gone.
  struct State {
    Write write;
    std::mutex mutex;
    std::condition_variable wake;                                  // something to write, or stop
    std::condition_variable written;                               // nothing left to write
    std::map<std::string, std::vector<KeptTimedCommand>> pending;  // device -> newest list
    bool writing = false;
    bool stopping = false;
  };
  static void run(const std::shared_ptr<State>& state);

  Read read_;
  std::shared_ptr<State> state_;
  std::thread thread_;
};

}  // namespace modbus_rtu_driver
