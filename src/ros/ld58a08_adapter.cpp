// LD58A08: PWM channels (set_pwm / stop_pwm services, pwm topic read back from the device).
#include "modbus_rtu_driver/PwmStates.h"
#include "modbus_rtu_driver/SetPwm.h"
#include "modbus_rtu_driver/StopPwm.h"
#include "modbus_rtu_driver/devices/ld58a08.h"
#include "modbus_rtu_driver/ros/adapter_registry.h"
#include "modbus_rtu_driver/ros/last_published.h"

namespace modbus_rtu_driver {

namespace {

class Ld58a08Adapter : public DeviceAdapter {
 public:
  using DeviceAdapter::DeviceAdapter;

  void advertise() override {
    pwm_pub_ = nh_.advertise<PwmStates>("pwm", 1, true);
    set_srv_ = nh_.advertiseService("set_pwm", &Ld58a08Adapter::onSetPwm, this);
    stop_srv_ = nh_.advertiseService("stop_pwm", &Ld58a08Adapter::onStopPwm, this);
  }

 private:
  Ld58a08& board() { return static_cast<Ld58a08&>(*device_); }

  void onPoll(size_t group, const Result& result) override {
    DeviceAdapter::onPoll(group, result);
    if (result.ok()) publishPwm();
  }

  // After a command (a PWM command's read back included): what the board runs now.
  void onChanged() override {
    DeviceAdapter::onChanged();
    publishPwm();
  }

  // Bus thread: publish the PWM settings when they changed.
  void publishPwm() {
    if (!board().pwmKnown()) return;
    PwmStates msg;
    for (const PwmState& s : board().pwm()) {
      PwmChannel c;
      c.channel = s.channel;
      c.high_speed = s.high_speed;
      c.running = s.running;
      c.continuous = s.continuous;
      c.period = s.period;
      c.on_time = s.on_time;
      c.remaining_pulses = s.remaining_pulses;
      c.frequency = s.frequency;
      c.duty_cycle = s.duty_cycle;
      c.remaining_time = s.remaining_time;
      msg.channels.push_back(c);
    }
    if (!last_pwm_.changed(msg)) return;
    msg.header.stamp = ros::Time::now();
    publishLater(pwm_pub_, std::move(msg));
  }

  bool onSetPwm(SetPwm::Request& req, SetPwm::Response& res) {
    PwmSettings s;
    s.channel = req.channel;
    s.period = req.period;
    s.on_time = req.on_time;
    s.pulses = req.pulses;
    s.frequency = req.frequency;
    s.duty_cycle = req.duty_cycle;
    s.duration = req.duration;
    // Checked there (refused: nothing queued); the PWM drives the output from now on.
    const Result r = unit().setPwm(s).get();
    res.success = r.ok();
    res.message = answer(r, "PWM set on channel " + std::to_string(s.channel));
    return true;
  }

  bool onStopPwm(StopPwm::Request& req, StopPwm::Response& res) {
    const uint8_t channel = req.channel;
    const Result r = unit().stopPwm(channel).get();
    res.success = r.ok();
    res.message = answer(r, "PWM stopped on channel " + std::to_string(channel));
    return true;
  }

  ros::Publisher pwm_pub_;
  ros::ServiceServer set_srv_, stop_srv_;
  LastPublished<PwmStates> last_pwm_;
};

}  // namespace

// `type: ld58a08` devices get this adapter (ros/adapter_registry.h).
[[maybe_unused]] const bool kLd58a08AdapterRegistered =
    adapterClasses().add(kLd58a08Type, makeAdapter<Ld58a08Adapter>);

}  // namespace modbus_rtu_driver
