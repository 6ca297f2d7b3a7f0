#include "modbus_rtu_driver/devices/device.h"

#include <algorithm>
#include <map>
#include <set>

#include "modbus_rtu_driver/core/modbus/text.h"

namespace modbus_rtu_driver {

std::vector<std::string> withDefaults(const std::vector<std::string>& given, size_t n,
                                      const char* prefix) {
  if (given.size() == n) return given;
  std::vector<std::string> names;
  names.reserve(n);
  for (size_t i = 0; i < n; ++i) names.push_back(prefix + std::to_string(i));
  return names;
}

std::vector<std::string> Device::outputNames() const {
  return withDefaults(config_.outputs, outputCount(), "out");
}

std::vector<std::string> Device::inputNames() const {
  return withDefaults(config_.inputs, inputCount(), "in");
}

std::string Device::checkOutputs(const std::vector<uint8_t>& channels,
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

std::vector<CoilRun> coilRuns(const std::vector<uint8_t>& channels,
                              const std::vector<bool>& states) {
  std::map<uint8_t, bool> sorted;
  for (size_t i = 0; i < channels.size() && i < states.size(); ++i) sorted[channels[i]] = states[i];
  std::vector<CoilRun> runs;
  for (const auto& [channel, state] : sorted) {
    if (runs.empty() || runs.back().first + runs.back().states.size() != channel)
      runs.push_back(CoilRun{channel, {}});
    runs.back().states.push_back(state);
  }
  return runs;
}

OutputTargets Device::outputsWrittenBy(const Request& request) const {
  OutputTargets set;
  if (request.function != FunctionCode::kWriteSingleCoil &&
      request.function != FunctionCode::kWriteMultipleCoils)
    return set;
  for (size_t i = 0; i < request.values.size(); ++i) {
    const size_t coil = request.address + i;
    if (coil >= outputCount()) break;
    set.channels.push_back(static_cast<uint8_t>(coil));
    set.states.push_back(request.values[i] == 1);
  }
  return set;
}

Result Device::writeOutputs(Transport& link, const std::vector<uint8_t>& channels,
                            const std::vector<bool>& states, std::vector<uint8_t>* changed,
                            const std::vector<bool>& timed_may_run) {
  // Only the channels asked for go on the wire: one frame per run of adjacent channels, so a
  // channel between two requested ones is never rewritten (a rewrite would cancel its flash
  // or fight its PWM on the board).
  const std::vector<CoilRun> runs = coilRuns(channels, states);
  std::vector<uint8_t> written;  // the channels of the runs confirmed so far, for a partial failure
  Result last = Result::success();
  for (const CoilRun& run : runs) {
    std::vector<uint8_t> run_channels;
    run_channels.reserve(run.states.size());
    for (size_t i = 0; i < run.states.size(); ++i)
      run_channels.push_back(static_cast<uint8_t>(run.first + i));
    Result r = run.states.size() == 1
                   ? link.execute(Request::writeSingleCoil(address(), run.first, run.states[0]))
                   : link.execute(Request::writeMultipleCoils(address(), run.first, run.states));
    if (!r.ok()) r = confirmCoils(link, std::move(r), run_channels, run.states, timed_may_run);
    if (!r.ok()) {
      if (changed) changed->insert(changed->end(), written.begin(), written.end());
      if (!written.empty())
        r.message += "; outputs " +
                     join(written, ", ", [](uint8_t c) { return std::to_string(c); }) +
                     " were written before, the others not";
      return r;
    }
    // The snapshot takes the run when the whole array is known (from a poll, or from
    // confirmCoils reading every coil back).
    if (outputs_.size() == outputCount())
      for (size_t i = 0; i < run.states.size(); ++i) outputs_[run.first + i] = run.states[i];
    written.insert(written.end(), run_channels.begin(), run_channels.end());
    if (!r.message.empty()) last.message += (last.message.empty() ? "" : "; ") + r.message;
    last.values = r.values;
  }
  if (outputs_.size() != outputCount() && channels.size() == outputCount()) {
    // Every channel written and confirmed: now the whole array is known.
    outputs_.assign(outputCount(), false);
    for (const CoilRun& run : runs)
      for (size_t i = 0; i < run.states.size(); ++i) outputs_[run.first + i] = run.states[i];
  }
  return last;
}

bool Device::mayHaveActed(const Result& r) {
  return answerLost(r.error);
}

// A write whose reply was lost may still have been done: the coils read back tell. Success
// only when they show every requested state; the snapshot takes what was read.
Result Device::confirmCoils(Transport& link, Result failed, const std::vector<uint8_t>& channels,
                            const std::vector<bool>& states,
                            const std::vector<bool>& timed_may_run) {
  if (!mayHaveActed(failed)) return failed;
  for (uint8_t ch : channels) {
    if (ch >= timed_may_run.size() || !timed_may_run[ch]) continue;
    // Not read: the level a read shows there may be the timed command's, not the write's.
    failed.message +=
        "; not confirmed: a timed command (flash or PWM run) may still drive output " +
        std::to_string(ch) + ", and a read cannot tell whether the write ended it";
    return failed;
  }
  Result now = link.execute(Request::readCoils(address(), 0, static_cast<uint16_t>(outputCount())));
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
