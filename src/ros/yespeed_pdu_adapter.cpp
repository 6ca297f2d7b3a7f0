// Yespeed PDU: telemetry every poll, limits latched, set_limits.
#include "modbus_rtu_driver/PduLimits.h"
#include "modbus_rtu_driver/PduTelemetry.h"
#include "modbus_rtu_driver/SetPduLimits.h"
#include "modbus_rtu_driver/devices/yespeed_pdu.h"
#include "modbus_rtu_driver/ros/adapter_registry.h"
#include "modbus_rtu_driver/ros/last_published.h"

namespace modbus_rtu_driver {

namespace {

class YespeedPduAdapter : public DeviceAdapter {
 public:
  using DeviceAdapter::DeviceAdapter;

  void advertise() override {
    telemetry_pub_ = nh_.advertise<PduTelemetry>("telemetry", 50);
    limits_pub_ = nh_.advertise<PduLimits>("limits", 1, true);
    set_limits_srv_ = nh_.advertiseService("set_limits", &YespeedPduAdapter::onSetLimits, this);
  }

 private:
  YespeedPdu& pdu() { return static_cast<YespeedPdu&>(*device_); }

  void onPoll(size_t group, const Result& result) override {
    DeviceAdapter::onPoll(group, result);
    // A failed read publishes nothing rather than an old value.
    if (pdu().readingFresh()) {
      const PduReading& r = pdu().reading();
      PduTelemetry msg;
      msg.header.stamp = ros::Time::now();
      msg.temperature = static_cast<float>(r.temperature);
      msg.humidity = static_cast<float>(r.humidity);
      msg.voltage = static_cast<float>(r.voltage);
      msg.current = static_cast<float>(r.current);
      msg.power = static_cast<float>(r.power);
      publishLater(telemetry_pub_, msg);
    }
    publishLimits();
  }

  // Bus thread: a write changed the device (set_limits reads the limits back): they are
  // published as the device holds them, with its outputs.
  void onChanged() override {
    DeviceAdapter::onChanged();
    publishLimits();
  }

  void publishLimits() {
    if (!pdu().limitsKnown()) return;
    const PduLimitValues& l = pdu().limits();
    PduLimits msg;
    msg.over_voltage = static_cast<float>(l.over_voltage);
    msg.under_voltage = static_cast<float>(l.under_voltage);
    msg.over_current = static_cast<float>(l.over_current);
    if (!last_limits_.changed(msg)) return;
    publishLater(limits_pub_, msg);
  }

  // A field left at 0 (the default of a field not given) keeps what the device holds: the
  // node reads the limits first and checks the rules on the merged values.
  bool onSetLimits(SetPduLimits::Request& req, SetPduLimits::Response& res) {
    const Result r = unit()
                         .setPduLimits(req.limits.over_voltage, req.limits.under_voltage,
                                       req.limits.over_current)
                         .get();
    res.success = r.ok();
    res.message = answer(r, "limits set");
    return true;
  }

  ros::Publisher telemetry_pub_, limits_pub_;
  ros::ServiceServer set_limits_srv_;
  LastPublished<PduLimits> last_limits_;
};

}  // namespace

// `type: yespeed_pdu` devices get this adapter (ros/adapter_registry.h).
[[maybe_unused]] const bool kYespeedPduAdapterRegistered =
    adapterClasses().add(kYespeedPduType, makeAdapter<YespeedPduAdapter>);

}  // namespace modbus_rtu_driver
