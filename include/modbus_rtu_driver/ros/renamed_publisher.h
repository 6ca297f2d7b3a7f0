// A topic renamed in this release. Its old name is still advertised for one release, with the
// same messages, so that a user's subscriber keeps working; the first subscriber on the old
// name logs a warning naming the new one, so the user learns of it before the old name goes.
#pragma once

#include <ros/ros.h>

#include <boost/make_shared.hpp>
#include <string>
#include <utility>

namespace modbus_rtu_driver {

// Logs "<old> is deprecated, use <name>; removed in the next release" once per old name and
// process (ROS_WARN_ONCE would warn once per call site, for the first old name used only).
void warnRenamed(const std::string& old_name, const std::string& name);

class RenamedPublisher {
 public:
  RenamedPublisher() = default;

  template <class Message>
  static RenamedPublisher advertise(ros::NodeHandle& nh, const std::string& name,
                                    const std::string& old_name, uint32_t queue_size,
                                    bool latch = false) {
    RenamedPublisher p;
    p.current_ = nh.advertise<Message>(name, queue_size, latch);
    const std::string resolved_old = nh.resolveName(old_name);
    const std::string resolved = nh.resolveName(name);
    p.old_ = nh.advertise<Message>(
        old_name, queue_size,
        [resolved_old, resolved](const ros::SingleSubscriberPublisher&) {
          warnRenamed(resolved_old, resolved);
        },
        ros::SubscriberStatusCallback(), ros::VoidConstPtr(), latch);
    return p;
  }

  // By shared pointer, as publishShared (publish_shared.h): one message for both names.
  template <class Message>
  void publish(Message message) const {
    const auto shared = boost::make_shared<const Message>(std::move(message));
    current_.publish(shared);
    old_.publish(shared);
  }

 private:
  ros::Publisher current_, old_;
};

}  // namespace modbus_rtu_driver
