// LC relay board: timed flash-close / flash-open (its inputs are published by the base).
#include "modbus_rtu_driver/Pulse.h"
#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/ros/adapter_registry.h"

namespace modbus_rtu_driver {

namespace {

class LcRelay8Adapter : public DeviceAdapter {
 public:
  using DeviceAdapter::DeviceAdapter;

  void advertise() override {
    pulse_srv_ = nh_.advertiseService("pulse", &LcRelay8Adapter::onPulse, this);
  }

 private:
  LcRelay8& board() { return static_cast<LcRelay8&>(*device_); }

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
    // Flash-close: on for `duration`, then off by itself; flash-open the other way round.
    const Result r =
        commands()
            .timed(
                TimedIntent{channel, state, !state, duration},
                [this, channel, state, duration](Transport& t) {
                  return board().pulse(t, channel, state, duration);
                },
                // The board changed the output by itself: read it back so the topics show it now.
                [this](Transport& t) {
                  if (board().poll(t).ok()) publishOutputs();
                })
            .get();
    res.success = r.ok();
    res.message =
        answer(r, std::string(state ? "flash-close " : "flash-open ") +
                      device_->outputNames()[channel] + " for " + numberText(duration) + " s");
    return true;
  }

  ros::ServiceServer pulse_srv_;
};

}  // namespace

// `type: lc_relay8` devices get this adapter (ros/adapter_registry.h).
[[maybe_unused]] const bool kLcRelay8AdapterRegistered =
    adapterClasses().add(kLcRelay8Type, makeAdapter<LcRelay8Adapter>);

}  // namespace modbus_rtu_driver
