// Generic device: one latched topic per signal (published on change), D/signals with every
// signal after each poll, D/<name>/set for writable signals, one poll per rate group.
#include <std_msgs/Float64.h>

#include <sstream>

#include "modbus_rtu_driver/SetValue.h"
#include "modbus_rtu_driver/SignalValues.h"
#include "modbus_rtu_driver/devices/generic_device.h"
#include "modbus_rtu_driver/ros/adapter_registry.h"

namespace modbus_rtu_driver {

namespace {

class GenericAdapter : public DeviceAdapter {
 public:
  using DeviceAdapter::DeviceAdapter;

  void advertise() override {
    const auto& signals = generic().signals();
    published_.assign(signals.size(), std::nullopt);
    all_pub_ = nh_.advertise<SignalValues>("signals", 50);
    for (size_t i = 0; i < signals.size(); ++i) {
      const SignalConfig& s = signals[i];
      const bool bit = s.type == SignalType::kBool;
      pubs_.push_back(bit ? nh_.advertise<std_msgs::Bool>(s.name, 1, true)
                          : nh_.advertise<std_msgs::Float64>(s.name, 1, true));
      if (!s.writable) continue;
      if (bit)
        services_.push_back(
            nh_.advertiseService<std_srvs::SetBool::Request, std_srvs::SetBool::Response>(
                s.name + "/set",
                [this, i](std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res) {
                  const Result r = write(i, req.data ? 1.0 : 0.0);
                  res.success = r.ok();
                  res.message =
                      answer(r, generic().signals()[i].name + (req.data ? " on" : " off"));
                  return true;
                }));
      else
        services_.push_back(nh_.advertiseService<SetValue::Request, SetValue::Response>(
            s.name + "/set", [this, i](SetValue::Request& req, SetValue::Response& res) {
              const Result r = write(i, req.value);
              res.success = r.ok();
              std::ostringstream what;
              what << generic().signals()[i].name << " set to " << req.value;
              res.message = answer(r, what.str());
              return true;
            }));
    }
  }

  // One poll per rate group with signals in it: fast values do not drag slow ones along.
  void addPolls() override {
    for (size_t g = 0; g < generic().groups().size(); ++g) {
      if (generic().groups()[g].signals.empty()) continue;
      auto device = device_;
      bus_.addPoll(
          device_->name(), generic().groups()[g].rate,
          [device, g](Transport& t) {
            return static_cast<GenericDevice&>(*device).pollGroup(t, g);
          },
          [this](const Result& r) { onPoll(r); });
    }
  }

  void diagnoseType(diagnostic_updater::DiagnosticStatusWrapper& status) override {
    // Read on the diagnostics thread: the split list only grows, and copies are taken whole.
    std::vector<std::string> splits;
    {
      std::lock_guard<std::mutex> lock(splits_mutex_);
      splits = splits_;
    }
    status.add("signals", generic().signals().size());
    for (size_t g = 0; g < generic().groups().size(); ++g) {
      const auto& group = generic().groups()[g];
      if (group.signals.empty()) continue;
      std::ostringstream key;
      key << "poll group " << g << " [Hz]";
      status.add(key.str(), group.rate);
    }
    status.add("merged reads split (device refused them)", splits.size());
    for (size_t k = 0; k < splits.size(); ++k) status.add("split " + std::to_string(k), splits[k]);
  }

 private:
  GenericDevice& generic() const { return static_cast<GenericDevice&>(*device_); }

  // No outputs (the base's topics stay silent, no restart detection): only the signals.
  void onPoll(const Result&) override { publishSignals(true); }

  Result write(size_t i, double value) {
    std::vector<uint16_t> words;
    const std::string problem = generic().encodeWrite(i, value, &words);
    if (!problem.empty()) return Result::failure(ErrorKind::kInvalidArgument, problem);
    return runOnBus([this, i, value](Transport& t) {
      Result r = generic().writeSignal(t, i, value);
      publishSignals(false);
      return r;
    });
  }

  // Bus thread: each signal's topic when its value changed, D/signals after a poll.
  void publishSignals(bool after_poll) {
    const auto& signals = generic().signals();
    const auto& states = generic().states();
    SignalValues all;
    all.header.stamp = ros::Time::now();
    for (size_t i = 0; i < signals.size(); ++i) {
      const SignalState& st = states[i];
      all.names.push_back(signals[i].name);
      all.values.push_back(st.value);
      all.valid.push_back(st.valid);
      if (!st.valid || (published_[i] && *published_[i] == st.value)) continue;
      published_[i] = st.value;
      if (signals[i].type == SignalType::kBool) {
        std_msgs::Bool m;
        m.data = st.value != 0.0;
        pubs_[i].publish(m);
      } else {
        std_msgs::Float64 m;
        m.data = st.value;
        pubs_[i].publish(m);
      }
    }
    if (after_poll) all_pub_.publish(all);
    std::lock_guard<std::mutex> lock(splits_mutex_);
    splits_ = generic().splits();
  }

  ros::Publisher all_pub_;
  std::vector<ros::Publisher> pubs_;
  std::vector<ros::ServiceServer> services_;
  std::vector<std::optional<double>> published_;  // bus thread only
  std::mutex splits_mutex_;
  std::vector<std::string> splits_;  // a copy for the diagnostics thread
};

}  // namespace

std::unique_ptr<DeviceAdapter> makeGenericAdapter(std::shared_ptr<Device> device, BusScheduler& bus,
                                                  const ros::NodeHandle& nh) {
  return std::make_unique<GenericAdapter>(std::move(device), bus, nh);
}

}  // namespace modbus_rtu_driver
