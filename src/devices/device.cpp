#include "modbus_rtu_driver/devices/device.h"

#include <algorithm>
#include <set>

namespace modbus_rtu_driver {

std::vector<std::string> withDefaults(const std::vector<std::string>& given, size_t n,
                                      const char* prefix) {
  if (given.size() == n) return given;
  std::vector<std::string> names;
  for (size_t i = 0; i < n; ++i) names.push_back(prefix + std::to_string(i));
  return names;
}

std::vector<std::string> Device::outputNames() const {
  return withDefaults(config_.outputs, outputCount(), "out");
}

std::vector<std::string> Device::inputNames() const {
  return withDefaults(config_.inputs, inputCount(), "in");
}

std::string Device::validateChannels(const std::vector<uint8_t>& channels,
                                     const std::vector<bool>& states) const {
  if (outputCount() == 0) return std::string("channels: a ") + type() + " device has no outputs";
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
    if (!r.ok()) return confirmCoils(bus, std::move(r), channels, states);
    if (target.size() == outputCount()) {
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
  if (!r.ok()) return confirmCoils(bus, std::move(r), channels, states);
  // The whole array is known only if it was read or already known before.
  if (r.ok() &&
      (span != channels.size() || span == outputCount() || outputs_.size() == outputCount()))
    outputs_ = target;
  return r;
}

bool Device::mayHaveActed(const Result& r) {
  return answerLost(r.error);
}

// A write whose reply was lost may still have been done: the coils read back tell. Success
// only when they show every requested state; the snapshot takes what was read.
Result Device::confirmCoils(Transport& bus, Result failed, const std::vector<uint8_t>& channels,
                            const std::vector<bool>& states) {
  if (!mayHaveActed(failed)) return failed;
  Result now = bus.execute(Request::readCoils(address(), 0, static_cast<uint16_t>(outputCount())));
  if (!now.ok()) {
    failed.message += "; not confirmed: reading the outputs back failed too (" + now.message + ")";
    return failed;
  }
  outputs_.assign(now.values.begin(), now.values.end());
  for (size_t i = 0; i < channels.size(); ++i) {
    if (outputs_[channels[i]] != states[i]) {
      failed.message += "; read back: not done (output " + std::to_string(channels[i]) + " is " +
                        (outputs_[channels[i]] ? "on" : "off") + ")";
      return failed;
    }
  }
  Result ok = Result::success();
  ok.message = "confirmed by reading the outputs back (" + failed.message + ")";
  return ok;
}

}  // namespace modbus_rtu_driver
