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
  bool onPulse(Pulse::Request& req, Pulse::Response& res) {
    const uint8_t channel = req.channel;
    const bool state = req.state;
    const double duration = req.duration;
    // Checked there (refused: nothing queued). Flash-close: on for `duration`, then off by
    // itself; flash-open the other way round.
    const Result r = unit().pulse(channel, state, duration).get();
    res.success = r.ok();
    // Refused, the channel may be outside the board's: the refusal names it.
    res.message = r.ok() ? answer(r, std::string(state ? "flash-close " : "flash-open ") +
                                         device_->outputNames()[channel] + " for " +
                                         numberText(duration) + " s")
                         : answer(r, "");
    return true;
  }

  ros::ServiceServer pulse_srv_;
};

}  // namespace

// `type: lc_relay8` devices get this adapter (ros/adapter_registry.h).
[[maybe_unused]] const bool kLcRelay8AdapterRegistered =
    adapterClasses().add(kLcRelay8Type, makeAdapter<LcRelay8Adapter>);

}  // namespace modbus_rtu_driver
