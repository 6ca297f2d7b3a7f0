// LC relay board: inputs (optocouplers) and timed flash-close / flash-open.
#include "modbus_rtu_driver/DigitalStates.h"
#include "modbus_rtu_driver/Pulse.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/ros/adapter_registry.h"

namespace modbus_rtu_driver {

namespace {

class LcRelay8Adapter : public DeviceAdapter {
 public:
  using DeviceAdapter::DeviceAdapter;

  void start() override {
    DeviceAdapter::start();
    const auto names = device_->inputNames();
    inputs_pub_ = nh_.advertise<DigitalStates>("inputs", 10);
    published_inputs_.assign(names.size(), std::nullopt);
    for (const auto& n : names)
      input_state_pubs_.push_back(nh_.advertise<std_msgs::Bool>(n + "/state", 1, true));
    pulse_srv_ = nh_.advertiseService("pulse", &LcRelay8Adapter::onPulse, this);
  }

 private:
  LcRelay8& board() { return static_cast<LcRelay8&>(*device_); }

  void onPoll(const Result& result) override {
    DeviceAdapter::onPoll(result);
    if (!result.ok()) return;
    const auto& states = device_->inputs();
    DigitalStates msg;
    msg.header.stamp = ros::Time::now();
    msg.states.assign(states.begin(), states.end());
    msg.names = device_->inputNames();
    inputs_pub_.publish(msg);
    for (size_t i = 0; i < states.size() && i < published_inputs_.size(); ++i) {
      if (published_inputs_[i] == states[i]) continue;
      published_inputs_[i] = states[i];
      std_msgs::Bool b;
      b.data = states[i];
      input_state_pubs_[i].publish(b);
    }
  }

  bool onPulse(Pulse::Request& req, Pulse::Response& res) {
    const std::string problem = LcRelay8::validatePulse(req.channel, req.duration);
    if (!problem.empty()) {
      res.success = false;
      res.message = device_->name() + ": " + problem;
      return true;
    }
    const uint8_t channel = req.channel;
    const bool state = req.state;
    const double duration = req.duration;
    const Result r = runOnBus([this, channel, state, duration](Transport& t) {
      Result w = board().pulse(t, channel, state, duration);
      // The board changed the output by itself: read it back so the topics show it now.
      if (w.ok() && board().poll(t).ok()) publishOutputs();
      return w;
    });
    res.success = r.ok();
    res.message =
        answer(r, std::string(state ? "flash-close " : "flash-open ") +
                      device_->outputNames()[channel] + " for " + std::to_string(duration) + " s");
    return true;
  }

  ros::Publisher inputs_pub_;
  std::vector<ros::Publisher> input_state_pubs_;
  std::vector<std::optional<bool>> published_inputs_;
  ros::ServiceServer pulse_srv_;
};

}  // namespace

std::unique_ptr<DeviceAdapter> makeLcRelay8Adapter(std::shared_ptr<Device> device,
                                                   BusScheduler& bus, const ros::NodeHandle& nh) {
  return std::make_unique<LcRelay8Adapter>(std::move(device), bus, nh);
}

}  // namespace modbus_rtu_driver
