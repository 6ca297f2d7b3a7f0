#include "modbus_rtu_driver/devices/ld58a08.h"

#include <cmath>
#include <cstdio>

namespace modbus_rtu_driver {

namespace {

constexpr uint16_t kContinuous = 0xFFFF;

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Tenths of a second, if `seconds` is a whole number of them (within float noise).
bool toTenths(double seconds, long* tenths) {
  const double t = seconds * 10.0;
  *tenths = std::lround(t);
  return std::fabs(t - static_cast<double>(*tenths)) < 1e-6;
}

}  // namespace

std::string Ld58a08::validatePwm(const PwmSettings& s) {
  if (s.channel >= kChannels) return "channel: " + std::to_string(s.channel) + " is outside 0-7";
  long t = 0;
  if (s.channel < 6) {
    if (!(s.period >= 0.1 && s.period <= 6553.5) || !toTenths(s.period, &t))
      return "period: " + fmt(s.period) + " s is outside 0.1-6553.5 s in steps of 0.1 s";
    if (!(s.on_time >= 0.0 && s.on_time <= 6553.4) || !toTenths(s.on_time, &t))
      return "on_time: " + fmt(s.on_time) + " s is outside 0-6553.4 s in steps of 0.1 s";
    if (s.on_time > s.period + 1e-9)
      return "on_time: " + fmt(s.on_time) + " s is longer than the period (" + fmt(s.period) +
             " s)";
    if (s.pulses == kContinuous) return "pulses: 65535 is outside 0-65534 (0 = run continuously)";
    return {};
  }
  if (!(s.frequency >= 1 && s.frequency <= 20000) || s.frequency != std::floor(s.frequency))
    return "frequency: " + fmt(s.frequency) + " Hz is outside 1-20000 Hz in whole Hz";
  if (!(s.duty_cycle >= 0 && s.duty_cycle <= 100) || s.duty_cycle != std::floor(s.duty_cycle))
    return "duty_cycle: " + fmt(s.duty_cycle) + " % is outside 0-100 % in whole percent";
  if (s.duration != 0.0 &&
      (!(s.duration >= 0.1 && s.duration <= 6553.4) || !toTenths(s.duration, &t)))
    return "duration: " + fmt(s.duration) +
           " s is outside 0.1-6553.4 s in steps of 0.1 s (0 = run continuously)";
  return {};
}

Result Ld58a08::setPwm(Transport& bus, const PwmSettings& s) {
  const std::string problem = validatePwm(s);
  if (!problem.empty()) return Result::failure(ErrorKind::kInvalidArgument, problem);
  std::vector<uint16_t> regs;
  long t = 0;
  if (s.channel < 6) {
    toTenths(s.period, &t);
    regs.push_back(static_cast<uint16_t>(t));
    toTenths(s.on_time, &t);
    regs.push_back(static_cast<uint16_t>(t));
    regs.push_back(s.pulses == 0 ? kContinuous : s.pulses);
  } else {
    regs.push_back(static_cast<uint16_t>(s.frequency));
    regs.push_back(static_cast<uint16_t>(s.duty_cycle));
    if (s.duration == 0.0) {
      regs.push_back(kContinuous);
    } else {
      toTenths(s.duration, &t);
      regs.push_back(static_cast<uint16_t>(t));
    }
  }
  Request write = Request::writeMultipleRegisters(address(), pwmRegister(s.channel), regs);
  write.repeatable = false;  // a second copy would restart the run: more pulses than asked for
  Result r = bus.execute(write);
  if (r.ok() || !mayHaveActed(r)) return r;
  return confirmPwm(bus, std::move(r), s.channel, regs);
}

// A PWM write whose reply was lost: the channel's registers tell whether it runs with what was
// written (a burst counts its pulses down, a timed fast run its time). Never sent again.
Result Ld58a08::confirmPwm(Transport& bus, Result failed, uint8_t ch,
                           const std::vector<uint16_t>& written) {
  PwmState state;
  Result now = readPwmChannel(bus, ch, &state);
  if (!now.ok()) {
    failed.message += "; not confirmed: reading channel " + std::to_string(ch) +
                      " back failed too (" + now.message + "); not sent again";
    return failed;
  }
  pwm_[ch] = state;
  const std::vector<uint16_t>& v = now.values;
  const bool runs = v[0] == written[0] && v[1] == written[1] && v[2] != 0 &&
                    (written[2] == kContinuous ? v[2] == kContinuous : v[2] <= written[2]);
  if (!runs) {
    failed.message += "; read back: channel " + std::to_string(ch) +
                      " does not run these settings (not started, or already finished); not "
                      "sent again, since a second copy could run it twice";
    return failed;
  }
  Result ok = Result::success(written);
  ok.message =
      "confirmed by reading channel " + std::to_string(ch) + " back (" + failed.message + ")";
  return ok;
}

Result Ld58a08::stopPwm(Transport& bus, uint8_t channel) {
  if (channel >= kChannels)
    return Result::failure(ErrorKind::kInvalidArgument,
                           "channel: " + std::to_string(channel) + " is outside 0-7");
  return bus.execute(Request::writeSingleRegister(address(), pwmRegister(channel) + 2, 0));
}

Result Ld58a08::readPwmChannel(Transport& bus, uint8_t ch, PwmState* out) {
  Result r = bus.execute(Request::readHoldingRegisters(address(), pwmRegister(ch), 3));
  if (!r.ok()) return r;
  PwmState& p = *out;
  p = PwmState{};
  p.channel = ch;
  p.high_speed = ch >= 6;
  const uint16_t enable = r.values[2];
  p.running = enable != 0;
  if (p.high_speed) {
    p.frequency = r.values[0];
    p.duty_cycle = r.values[1];
    p.duration = enable / 10.0;
  } else {
    p.period = r.values[0] / 10.0;
    p.on_time = r.values[1] / 10.0;
    p.pulses = enable;
  }
  return r;
}

Result Ld58a08::readPwm(Transport& bus) {
  std::array<PwmState, kChannels> states{};
  for (uint8_t ch = 0; ch < kChannels; ++ch) {
    Result r = readPwmChannel(bus, ch, &states[ch]);
    if (!r.ok()) return r;
  }
  pwm_ = states;
  pwm_known_ = true;
  return Result::success();
}

Result Ld58a08::poll(Transport& bus) {
  Result r = bus.execute(Request::readCoils(address(), 0, kChannels));
  if (!r.ok()) return r;
  outputs_.assign(r.values.begin(), r.values.end());
  if (!pwm_known_) return readPwm(bus);
  // The manual allows reading 1-3 registers at a time: one channel per poll keeps a poll at two
  // transactions, and a burst that ends on the board shows within 8 polls.
  const uint8_t ch = poll_cursor_;
  poll_cursor_ = static_cast<uint8_t>((poll_cursor_ + 1) % kChannels);
  return readPwmChannel(bus, ch, &pwm_[ch]);
}

Result Ld58a08::setOutputs(Transport& bus, const std::vector<uint8_t>& channels,
                           const std::vector<bool>& states) {
  return writeCoilOutputs(bus, channels, states);
}

Result Ld58a08::readSettings(Transport& bus, Ld58a08Settings* out) {
  Result r = bus.execute(Request::readHoldingRegisters(address(), kPowerDownSaveRegister, 6));
  if (!r.ok()) return r;
  out->power_down_save = r.values[0];
  out->return_delay = r.values[2];
  out->address = r.values[3];
  out->baud_code = r.values[4];
  out->parity = r.values[5];
  return r;
}

Result Ld58a08::setReturnDelay(Transport& bus, uint16_t units) {
  if (units > 25)
    return Result::failure(
        ErrorKind::kInvalidArgument,
        "return_delay: " + std::to_string(units) + " is outside 0-25 (x 40 ms, up to 1000 ms)");
  return bus.execute(Request::writeSingleRegister(address(), kReturnDelayRegister, units));
}

}  // namespace modbus_rtu_driver
