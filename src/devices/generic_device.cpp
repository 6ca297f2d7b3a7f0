#include "modbus_rtu_driver/devices/generic_device.h"

#include <cmath>
#include <cstddef>
#include <sstream>

#include "modbus_rtu_driver/devices/registry.h"

namespace modbus_rtu_driver {

// `type: generic` in the bus YAML builds this class (devices/registry.h).
[[maybe_unused]] const bool kGenericDeviceRegistered =
    deviceClasses().add(kGenericType, makeDevice<GenericDevice>);

namespace {

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

bool sameReading(double a, double b) {
  return a == b || (std::isnan(a) && std::isnan(b));
}

GenericDevice::GenericDevice(DeviceConfig config)
    : Device(kGenericType, std::move(config)),
      planner_(this->config().generic.signals, this->config().generic.max_gap) {
  states_.resize(signals().size());
  groups_.push_back({this->config().poll_rate, {}});
  for (size_t i = 0; i < signals().size(); ++i) {
    const double rate = signals()[i].poll_rate.value_or(this->config().poll_rate);
    size_t g = 0;
    while (g < groups_.size() && groups_[g].rate != rate) ++g;
    if (g == groups_.size()) groups_.push_back({rate, {}});
    groups_[g].signals.push_back(i);
  }
}

void GenericDevice::setFromWords(size_t i, const uint16_t* words) {
  const SignalConfig& s = signals()[i];
  SignalState& st = states_[i];
  const double raw = decodeRaw(s.type, s.word_order, words);
  st.value = s.type == SignalType::kBool ? raw : s.toValue(raw);
  st.valid = st.known = true;
}

bool GenericDevice::readSpan(Transport& link, const ReadSpan& span, Result* first_failure) {
  Result r = link.execute(span.request(address()));
  if (r.ok() && r.values.size() == span.count) {
    for (size_t i : span.signals) setFromWords(i, &r.values[signals()[i].address - span.address]);
    return true;
  }
  if (r.ok()) r = Result::failure(ErrorKind::kMalformed, "wrong number of values");
  ReadSpan a, b;
  // 02: an unmapped register in the gap; 03: a quantity longer than the device serves (Eastron
  // meters answer over-long reads so). Either way the parts may read where the whole did not.
  const bool refused_span =
      r.error == ErrorKind::kException &&
      (r.exception_code == kIllegalDataAddress || r.exception_code == kIllegalDataValue);
  if (refused_span && planner_.split(span, &a, &b, r.exception_code)) {
    if (readSpan(link, a, first_failure)) return readSpan(link, b, first_failure);
    for (size_t i : b.signals) states_[i].valid = false;
    return false;
  }
  for (size_t i : span.signals) states_[i].valid = false;
  if (first_failure->ok()) {
    *first_failure = r;
    first_failure->message = span.describe(signals()) + ": " + r.message;
  }
  return !noProperAnswer(r.error);
}

Result GenericDevice::pollGroup(Transport& link, size_t group) {
  Result failure = Result::success();
  const std::vector<ReadSpan> spans = planner_.plan(groups_.at(group).signals);
  for (size_t k = 0; k < spans.size(); ++k) {
    if (readSpan(link, spans[k], &failure)) continue;
    for (size_t rest = k + 1; rest < spans.size(); ++rest)  // not answering: stale, not asked
      for (size_t i : spans[rest].signals) states_[i].valid = false;
    break;
  }
  return failure;
}

Request GenericDevice::writeRequest(const SignalConfig& s,
                                    const std::vector<uint16_t>& words) const {
  switch (s.writeFunction()) {
    case 5:
      return Request::writeSingleCoil(address(), s.address, words[0] != 0);
    case 15:
      return Request::writeMultipleCoils(address(), s.address, {words[0] != 0});
    case 6:
      return Request::writeSingleRegister(address(), s.address, words[0]);
    default:  // 16 (encodeWrite refused the rest)
      return Request::writeMultipleRegisters(address(), s.address, words);
  }
}

std::string GenericDevice::encodeWrite(size_t i, double value, std::vector<uint16_t>* words) const {
  if (i >= signals().size()) return "signal: " + std::to_string(i) + " does not exist";
  const SignalConfig& s = signals()[i];
  if (!s.writable) return s.name + ": not writable";
  const std::string bad_function = writeFunctionProblem(s);
  if (!bad_function.empty()) return s.name + ": write_function " + bad_function;
  const std::string problem = writeValueProblem(s, value, words);
  return problem.empty() ? problem : s.name + ": " + problem;
}

Result GenericDevice::writeSignal(Transport& link, size_t i, double value) {
  std::vector<uint16_t> words;
  const std::string problem = encodeWrite(i, value, &words);
  if (!problem.empty()) return Result::failure(ErrorKind::kInvalidArgument, problem);
  const SignalConfig& s = signals()[i];
  const bool coil = s.table == Table::kCoil;
  Result r = link.execute(writeRequest(s, words));
  if (r.ok()) {
    setFromWords(i, words.data());
    return r;
  }
  if (!mayHaveActed(r)) return r;
  // The reply was lost: the device may have done it. Read it back to tell.
  const Request back = coil ? Request::readCoils(address(), s.address, 1)
                            : Request::readHoldingRegisters(address(), s.address, s.words());
  const Result now = link.execute(back);
  if (!now.ok()) {
    r.message += "; not confirmed: reading " + s.name + " back failed too (" + now.message + ")";
    return r;
  }
  if (now.values.size() == words.size()) setFromWords(i, now.values.data());
  if (now.values != words) {
    r.message += "; read back: not done (" + s.name + " is " + number(states_[i].value) + ")";
    return r;
  }
  Result ok = Result::success();
  ok.message = "confirmed by reading " + s.name + " back (" + r.message + ")";
  return ok;
}

std::vector<size_t> GenericDevice::safeSignals() const {
  std::vector<size_t> out;
  for (size_t i = 0; i < signals().size(); ++i)
    if (signals()[i].writable && signals()[i].safe_value) out.push_back(i);
  return out;
}

Result GenericDevice::writeSafeValues(Transport& link, const std::vector<size_t>& signals,
                                      std::vector<size_t>* not_reached) {
  Result first = Result::success();
  if (not_reached) not_reached->clear();
  for (size_t k = 0; k < signals.size(); ++k) {
    bool answered = true;
    const Result r = writeSafeValue(link, signals[k], &answered);
    if (r.ok()) continue;
    if (first.ok()) first = r;
    if (!answered) {
      // Silent: the others would only wait out their timeouts.
      if (not_reached)
        not_reached->assign(signals.begin() + static_cast<std::ptrdiff_t>(k), signals.end());
      break;
    }
  }
  return first;
}

Result GenericDevice::writeSafeValue(Transport& link, size_t i, bool* answered) {
  *answered = true;
  const SignalConfig& s = signals()[i];
  if (!s.safe_value)
    return Result::failure(ErrorKind::kInvalidArgument, s.name + ": no safe value");
  std::vector<uint16_t> words;
  const std::string problem = encodeWrite(i, *s.safe_value, &words);
  if (!problem.empty()) return Result::failure(ErrorKind::kInvalidArgument, problem);
  Result w = writeSignal(link, i, *s.safe_value);
  if (!w.ok()) {
    *answered = !noProperAnswer(w.error);
    w.message = s.name + ": " + w.message;
    return w;
  }
  const Request back = s.table == Table::kCoil
                           ? Request::readCoils(address(), s.address, 1)
                           : Request::readHoldingRegisters(address(), s.address, s.words());
  Result now = link.execute(back);
  if (!now.ok()) {
    *answered = !noProperAnswer(now.error);
    now.message = s.name + ": written, but reading back failed: " + now.message;
    return now;
  }
  if (now.values.size() == words.size()) setFromWords(i, now.values.data());
  if (now.values != words)
    return Result::failure(ErrorKind::kMalformed, "read back: " + s.name + " is " +
                                                      number(states_[i].value) + ", not " +
                                                      number(*s.safe_value));
  return Result::success();
}

}  // namespace modbus_rtu_driver
