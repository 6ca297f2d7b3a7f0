// One device's channel states on ROS: an array topic (DigitalStates, latched) and one latched
// std_msgs/Bool per channel, published on change. Used for outputs and inputs alike.
#pragma once

#include <ros/ros.h>

#include <optional>
#include <string>
#include <vector>

namespace modbus_rtu_driver {

class DigitalStatesPublisher {
 public:
  struct Policy {
    bool on_change = false;   // array only when a state changes (or stale changes) ...
    double keep_alive = 1.0;  // ... and at least every keep_alive s
  };

  // Advertises `topic` and `<name>/state` for each name under `nh`.
  DigitalStatesPublisher(ros::NodeHandle& nh, const std::string& topic,
                         std::vector<std::string> names, Policy policy);

  // Fresh states (a read or a confirmed write), stamped `stamp`.
  void publish(const std::vector<bool>& states, ros::Time stamp);
  // The device went offline: the last states again, marked stale (once, until fresh ones come).
  void markStale();

 private:
  void send(ros::Time stamp);

  ros::Publisher array_;
  std::vector<ros::Publisher> channels_;
  std::vector<std::string> names_;
  Policy policy_;
  std::vector<bool> states_;
  std::vector<std::optional<bool>> sent_channels_;
  ros::Time stamp_;
  bool stale_ = false;
  bool sent_any_ = false;
  ros::WallTime last_sent_;
};

}  // namespace modbus_rtu_driver
