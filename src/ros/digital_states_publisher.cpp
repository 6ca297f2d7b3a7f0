#include "modbus_rtu_driver/ros/digital_states_publisher.h"

#include <std_msgs/Bool.h>

#include "modbus_rtu_driver/DigitalStates.h"
#include "modbus_rtu_driver/ros/publish_shared.h"

namespace modbus_rtu_driver {

DigitalStatesPublisher::DigitalStatesPublisher(ros::NodeHandle& nh, const std::string& topic,
                                               std::vector<std::string> names, Policy policy)
    : names_(std::move(names)), policy_(policy), sent_channels_(names_.size()) {
  array_ = nh.advertise<DigitalStates>(topic, 10, true);
  for (const auto& n : names_)
    channels_.push_back(nh.advertise<std_msgs::Bool>(n + "/state", 1, true));
}

void DigitalStatesPublisher::publish(const std::vector<bool>& states, ros::Time stamp) {
  if (states.size() != names_.size()) return;  // not known yet
  const bool changed = !sent_any_ || stale_ || states != states_;
  states_ = states;
  stamp_ = stamp;
  stale_ = false;
  const bool due = (ros::WallTime::now() - last_sent_).toSec() >= policy_.keep_alive;
  if (!policy_.on_change || changed || due) send(stamp);
  for (size_t i = 0; i < states.size(); ++i) {
    if (sent_channels_[i] == states[i]) continue;
    sent_channels_[i] = states[i];
    std_msgs::Bool b;
    b.data = states[i];
    publishShared(channels_[i], b);
  }
}

void DigitalStatesPublisher::markStale() {
  if (stale_ || !sent_any_) return;
  stale_ = true;
  send(stamp_);  // the stamp of the read these states come from, not now
}

void DigitalStatesPublisher::send(ros::Time stamp) {
  DigitalStates msg;
  msg.header.stamp = stamp;
  msg.states.assign(states_.begin(), states_.end());
  msg.names = names_;
  msg.stale = stale_;
  publishShared(array_, std::move(msg));
  sent_any_ = true;
  last_sent_ = ros::WallTime::now();
}

}  // namespace modbus_rtu_driver
