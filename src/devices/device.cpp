#include "modbus_rtu_driver/devices/device.h"

#include <algorithm>
#include <set>

namespace modbus_rtu_driver {

namespace {
std::vector<std::string> withDefaults(const std::vector<std::string>& given, size_t n,
                                      const char* prefix) {
  if (given.size() == n) return given;
  std::vector<std::string> names;
  for (size_t i = 0; i < n; ++i) names.push_back(prefix + std::to_string(i));
  return names;
}
}  // namespace

std::vector<std::string> Device::outputNames() const {
  return withDefaults(config_.outputs, outputCount(), "out");
}

std::vector<std::string> Device::inputNames() const {
  return withDefaults(config_.inputs, inputCount(), "in");
}

std::string Device::validateChannels(const std::vector<uint8_t>& channels,
                                     const std::vector<bool>& states) const {
  if (channels.empty()) return "channels: empty, give at least one channel";
  if (states.size() != channels.size())
    return "states: " + std::to_string(states.size()) + " given for " +
           std::to_string(channels.size()) + " channels";
  std::set<uint8_t> seen;
  for (uint8_t c : channels) {
    if (c >= outputCount())
      return "channel: " + std::to_string(c) + " is outside 0-" + std::to_string(outputCount() - 1);
    if (!seen.insert(c).second) return "channel: " + std::to_string(c) + " is given twice";
  }
  return {};
}

Result Device::writeCoilOutputs(Transport& bus, const std::vector<uint8_t>& channels,
                                const std::vector<bool>& states) {
  const std::string problem = validateChannels(channels, states);
  if (!problem.empty()) return Result::failure(ErrorKind::kInvalidArgument, problem);
  std::vector<bool> target = outputs_;
  if (channels.size() == 1) {
    Result r = bus.execute(Request::writeSingleCoil(address(), channels[0], states[0]));
    if (r.ok() && target.size() == outputCount()) {
      target[channels[0]] = states[0];
      outputs_ = target;
    }
    return r;
  }
  const uint8_t lo = *std::min_element(channels.begin(), channels.end());
  const uint8_t hi = *std::max_element(channels.begin(), channels.end());
  const size_t span = hi - lo + 1u;
  if (span != channels.size()) {
    // Gaps in the span keep their state: read the coils now rather than trust an old poll.
    Result current =
        bus.execute(Request::readCoils(address(), 0, static_cast<uint16_t>(outputCount())));
    if (!current.ok()) return current;
    target.assign(current.values.begin(), current.values.end());
  } else if (target.size() != outputCount()) {
    target.assign(outputCount(), false);
  }
  for (size_t i = 0; i < channels.size(); ++i) target[channels[i]] = states[i];
  const std::vector<bool> bits(target.begin() + lo, target.begin() + hi + 1);
  Result r = bus.execute(Request::writeMultipleCoils(address(), lo, bits));
  // The whole array is known only if it was read or already known before.
  if (r.ok() &&
      (span != channels.size() || span == outputCount() || outputs_.size() == outputCount()))
    outputs_ = target;
  return r;
}

}  // namespace modbus_rtu_driver
