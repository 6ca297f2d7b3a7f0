#include "modbus_rtu_driver/devices/ld58a08.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/devices/registry.h"

namespace modbus_rtu_driver {

// `type: ld58a08` in the bus YAML builds this class (devices/registry.h).
[[maybe_unused]] const bool kLd58a08Registered =
    deviceClasses().add(kLd58a08Type, makeDevice<Ld58a08>);

namespace {

constexpr uint16_t kContinuous = 0xFFFF;

std::string fmt(double v) {
  return numberText(v);
}

// Tenths of a second, if `seconds` is a whole number of them (within float noise).
bool toTenths(double seconds, long* tenths) {
  const double t = seconds * 10.0;
  *tenths = std::lround(t);
  return std::fabs(t - static_cast<double>(*tenths)) < 1e-6;
}

// Range first ("outside"), then the step ("not a multiple of" / "not whole"): each message
// names the real problem.
std::string checkTenths(const char* field, double v, double lo, double hi, const char* note) {
  long t = 0;
  const std::string range = fmt(lo) + "-" + fmt(hi) + " s";
  const std::string what = std::string(field) + ": " + fmt(v) + " s is ";
  if (!(v >= lo && v <= hi))
    return what + "outside " + range + (*note ? std::string(" (") + note + ")" : "");
  if (!toTenths(v, &t))
    return what + "not a multiple of the 0.1 s step (" + range + " in steps of 0.1 s" +
           (*note ? std::string("; ") + note : "") + ")";
  return {};
}

std::string checkWhole(const char* field, double v, double lo, double hi, const char* unit,
                       const char* whole) {
  const std::string range = fmt(lo) + "-" + fmt(hi) + " " + unit;
  if (!(v >= lo && v <= hi))
    return std::string(field) + ": " + fmt(v) + " " + unit + " is outside " + range;
  if (v != std::floor(v))
    return std::string(field) + ": " + fmt(v) + " " + unit + " is not " + whole + " (" + range +
           " in steps of 1 " + unit + ")";
  return {};
}

}  // namespace

std::string Ld58a08::validatePwm(const PwmSettings& s) {
  if (s.channel >= kChannels) return "channel: " + std::to_string(s.channel) + " is outside 0-7";
  const std::string ch = "channel " + std::to_string(s.channel);
  std::string problem;
  if (s.channel < 6) {
    const char* wrong = s.frequency != 0.0    ? "frequency"
                        : s.duty_cycle != 0.0 ? "duty_cycle"
                        : s.duration != 0.0   ? "duration"
                                              : nullptr;
    if (wrong)
      return std::string(wrong) + ": " + ch +
             " takes period/on_time/pulses (channels 0-5); frequency/duty_cycle/duration are "
             "for channels 6-7";
    problem = checkTenths("period", s.period, 0.1, 6553.5, "");
    if (problem.empty()) problem = checkTenths("on_time", s.on_time, 0.0, 6553.4, "");
    if (!problem.empty()) return problem;
    if (s.on_time > s.period + 1e-9)
      return "on_time: " + fmt(s.on_time) + " s is longer than the period (" + fmt(s.period) +
             " s)";
    if (s.pulses == kContinuous) return "pulses: 65535 is outside 0-65534 (0 = run continuously)";
    return {};
  }
  const char* wrong = s.period != 0.0    ? "period"
                      : s.on_time != 0.0 ? "on_time"
                      : s.pulses != 0    ? "pulses"
                                         : nullptr;
  if (wrong)
    return std::string(wrong) + ": " + ch +
           " takes frequency/duty_cycle/duration (channels 6-7); period/on_time/pulses are for "
           "channels 0-5";
  problem = checkWhole("frequency", s.frequency, 1, 20000, "Hz", "a whole number of Hz");
  if (problem.empty())
    problem = checkWhole("duty_cycle", s.duty_cycle, 0, 100, "%", "a whole percent");
  if (!problem.empty()) return problem;
  if (s.duration != 0.0)
    return checkTenths("duration", s.duration, 0.1, 6553.4, "0 = run continuously");
  return {};
}

Result Ld58a08::setPwm(Transport& link, const PwmSettings& s) {
  const std::string problem = validatePwm(s);
  if (!problem.empty()) return Result::failure(ErrorKind::kInvalidArgument, problem);
  return writePwm(link, pwmWrite(s));
}

Request Ld58a08::pwmWrite(const PwmSettings& s) const {
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
  return write;
}

Result Ld58a08::writePwm(Transport& link, const Request& write) {
  const auto ch = static_cast<uint8_t>(write.address / 0x10);
  Result r = link.execute(write);
  if (!r.ok() && mayHaveActed(r)) r = confirmPwm(link, std::move(r), ch, write.values);
  if (r.ok() && write.values[2] == kContinuous) noteContinuousRun(ch);
  return r;
}

Result Ld58a08::startAgain(Transport& link, const Request& write) {
  // Only what pwmIntent and timedWrittenBy give as a run's restart: one channel's three
  // registers, a continuous run.
  if (write.slave != address() || write.function != FunctionCode::kWriteMultipleRegisters ||
      write.address % 0x10 != 0 || write.address / 0x10 >= kChannels || write.values.size() != 3 ||
      write.values[2] != kContinuous)
    return Result::failure(ErrorKind::kInvalidArgument,
                           "not a continuous PWM run of this board: " + write.describe());
  Request once = write;
  once.repeatable = false;
  return writePwm(link, once);
}

void Ld58a08::noteContinuousRun(uint8_t channel) {
  PwmState& p = pwm_[channel];
  p.enable = kContinuous;
  p.running = p.continuous = true;
  p.remaining_pulses = 0;
  p.remaining_time = 0.0;
}

// A PWM write whose reply was lost: the channel's registers tell whether it runs with what was
// written (a burst counts its pulses down, a timed fast run its time). Never sent again.
Result Ld58a08::confirmPwm(Transport& link, Result failed, uint8_t ch,
                           const std::vector<uint16_t>& written) {
  PwmState state;
  Result now = readPwmChannel(link, ch, &state);
  if (!now.ok()) {
    pwm_unsure_[ch] = true;
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

Result Ld58a08::stopPwm(Transport& link, uint8_t channel) {
  if (channel >= kChannels)
    return Result::failure(ErrorKind::kInvalidArgument,
                           "channel: " + std::to_string(channel) + " is outside 0-7");
  Result r = link.execute(Request::writeSingleRegister(address(), pwmRegister(channel) + 2, 0));
  if (r.ok() || !mayHaveActed(r)) return r;
  // The reply was lost: the enable register tells (0 = stopped, by this write or by itself).
  PwmState state;
  Result now = readPwmChannel(link, channel, &state);
  if (!now.ok()) {
    pwm_unsure_[channel] = true;
    r.message += "; not confirmed: reading channel " + std::to_string(channel) +
                 " back failed too (" + now.message + ")";
    return r;
  }
  pwm_[channel] = state;
  if (state.running) {
    r.message += "; read back: not done (channel " + std::to_string(channel) + " still runs)";
    return r;
  }
  Result ok = Result::success();
  ok.message =
      "confirmed by reading channel " + std::to_string(channel) + " back (" + r.message + ")";
  return ok;
}

Result Ld58a08::readPwmChannel(Transport& link, uint8_t ch, PwmState* out) {
  Result r = link.execute(Request::readHoldingRegisters(address(), pwmRegister(ch), 3));
  if (!r.ok()) return r;
  PwmState& p = *out;
  p = PwmState{};
  p.channel = ch;
  p.high_speed = ch >= 6;
  const uint16_t enable = r.values[2];
  p.enable = enable;
  p.running = enable != 0;
  p.continuous = enable == kContinuous;
  const uint16_t left = p.continuous ? 0 : enable;
  if (p.high_speed) {
    p.frequency = r.values[0];
    p.duty_cycle = r.values[1];
    p.remaining_time = left / 10.0;
  } else {
    p.period = r.values[0] / 10.0;
    p.on_time = r.values[1] / 10.0;
    p.remaining_pulses = left;
  }
  return r;
}

Result Ld58a08::readPwm(Transport& link) {
  // Each channel read is what the node knows of it from now on, also when a later channel's
  // read fails (docs/failsafe.md F31: a read that shows a run ended ends it); the snapshot is
  // known once every channel was read.
  for (uint8_t ch = 0; ch < kChannels; ++ch) {
    Result r = readPwmChannel(link, ch, &pwm_[ch]);
    if (!r.ok()) return r;
  }
  pwm_known_ = true;
  return Result::success();
}

Result Ld58a08::poll(Transport& link) {
  pwm_read_by_poll_.fill(false);
  // The PWM registers before the outputs (docs/devices/ld58a08.md): a run they show ended also
  // ended before the outputs were read, so the level read is not the run's last on phase (a
  // level the node finds, or takes for a write whose outcome was unknown). A run the registers
  // show stays the device's whatever the outputs show; none can start between the reads but by
  // a write, which the fail-safe sees.
  if (!pwm_known_) {
    // The first poll reads every channel.
    Result pwm = readPwm(link);
    if (!pwm.ok()) return pwm;
    pwm_read_by_poll_.fill(true);
    pwm_unsure_.fill(false);
  } else {
    // The manual allows reading 1-3 registers at a time: one channel per poll keeps a poll at
    // two transactions, and a burst that ends on the board shows within 8 polls. A channel whose
    // PWM write went unconfirmed goes first, out of turn.
    const auto unsure = std::find(pwm_unsure_.begin(), pwm_unsure_.end(), true);
    uint8_t ch = poll_cursor_;
    if (unsure != pwm_unsure_.end()) {
      ch = static_cast<uint8_t>(unsure - pwm_unsure_.begin());
    } else {
      poll_cursor_ = static_cast<uint8_t>((poll_cursor_ + 1) % kChannels);
    }
    Result pwm = readPwmChannel(link, ch, &pwm_[ch]);
    if (!pwm.ok()) return pwm;
    pwm_read_by_poll_[ch] = true;
    pwm_unsure_[ch] = false;
  }
  Result r = link.execute(Request::readCoils(address(), 0, kChannels));
  if (!r.ok()) return r;
  outputs_.assign(r.values.begin(), r.values.end());
  return r;
}

// The outputs (coils and register 0x0080) drive a channel only while its enable register is 0
// (manual, 0x0080): while the PWM runs, the board acknowledges the write and the output keeps
// following the PWM. So the requested channels' PWM registers are read first (the snapshot may
// be 8 polls old), a running PWM is stopped (confirmed), and then the outputs are written.
Result Ld58a08::writeOutputs(Transport& link, const std::vector<uint8_t>& channels,
                             const std::vector<bool>& states, std::vector<uint8_t>* changed,
                             const std::vector<bool>& timed_may_run) {
  std::vector<uint8_t> stopped;
  // A run stopped (confirmed) before the outputs failed stays stopped: the caller's failure
  // carries it (`changed`), so that the fail-safe does not take it as still running.
  auto failed = [&](Result r) {
    if (changed) changed->insert(changed->end(), stopped.begin(), stopped.end());
    return r;
  };
  auto list = [](const std::vector<uint8_t>& chs) {
    // uint8_t would print as a character through join's <<.
    return (chs.size() == 1 ? "channel " : "channels ") +
           join(chs, ", ", [](uint8_t c) { return std::to_string(c); });
  };
  auto stoppedNote = [&] { return "PWM on " + list(stopped) + " stopped first"; };
  for (uint8_t ch : channels) {
    PwmState state;
    Result read = readPwmChannel(link, ch, &state);
    if (!read.ok()) {
      read.message += "; outputs not written: whether PWM runs on channel " + std::to_string(ch) +
                      " is unknown";
      if (!stopped.empty()) read.message += " (" + stoppedNote() + ")";
      return failed(read);
    }
    pwm_[ch] = state;
    if (!state.running) continue;
    Result stop = stopPwm(link, ch);
    if (!stop.ok()) {
      stop.message = "PWM runs on channel " + std::to_string(ch) + " and stopping it failed (" +
                     stop.message + "); outputs not written";
      if (!stopped.empty()) stop.message += " (" + stoppedNote() + ")";
      return failed(stop);
    }
    pwm_[ch].running = pwm_[ch].continuous = false;
    pwm_[ch].remaining_pulses = 0;
    pwm_[ch].remaining_time = 0.0;
    pwm_[ch].enable = 0;
    stopped.push_back(ch);
  }
  // A run stopped here (confirmed) no longer drives its channel.
  std::vector<bool> may_run = timed_may_run;
  for (uint8_t ch : stopped)
    if (ch < may_run.size()) may_run[ch] = false;
  Result r = Device::writeOutputs(link, channels, states, changed, may_run);
  if (stopped.empty()) return r;
  if (r.ok()) {
    r.message = stoppedNote() + (r.message.empty() ? "" : "; " + r.message);
    return r;
  }
  r.message += " (" + stoppedNote() + ")";
  return failed(r);
}

Result Ld58a08::readSettings(Transport& link, Ld58a08Settings* out) {
  Result r = link.execute(Request::readHoldingRegisters(address(), kPowerDownSaveRegister, 6));
  if (!r.ok()) return r;
  out->power_down_save = r.values[0];
  out->return_delay = r.values[2];
  out->address = r.values[3];
  out->baud_code = r.values[4];
  out->parity = r.values[5];
  return r;
}

std::string Ld58a08::validateSetting(Ld58a08Setting setting, uint16_t value) {
  auto outside = [value](const char* field, int lo, int hi, const char* what) {
    if (value >= lo && value <= hi) return std::string();
    return std::string(field) + ": " + std::to_string(value) + " is outside " + std::to_string(lo) +
           "-" + std::to_string(hi) + what;
  };
  switch (setting) {
    case Ld58a08Setting::kPowerDownSave:
      return outside("power_down_save", 0, 1, " (0 off, 1 on)");
    case Ld58a08Setting::kReturnDelay:
      return outside("return_delay", 0, 25, " (x 40 ms, up to 1000 ms)");
    case Ld58a08Setting::kAddress:
      return outside("address", 1, static_cast<int>(kLd58a08Type.max_address), "");
    case Ld58a08Setting::kBaud:
      return outside("baud_code", 0, 7,
                     " (1200-115200; the board takes a higher code as a factory reset)");
    case Ld58a08Setting::kParity:
      return outside("parity", 0, 2, " (0 none, 1 even, 2 odd)");
  }
  return "unknown setting";
}

Result Ld58a08::readSetting(Transport& link, Ld58a08Setting setting, uint16_t* value) {
  Result r =
      link.execute(Request::readHoldingRegisters(address(), static_cast<uint16_t>(setting), 1));
  if (r.ok()) *value = r.values[0];
  return r;
}

Result Ld58a08::writeSetting(Transport& link, Ld58a08Setting setting, uint16_t value) {
  const std::string problem = validateSetting(setting, value);
  if (!problem.empty()) return Result::failure(ErrorKind::kInvalidArgument, problem);
  return link.execute(
      Request::writeSingleRegister(address(), static_cast<uint16_t>(setting), value));
}

Result Ld58a08::factoryReset(Transport& link) {
  return link.execute(Request::writeSingleRegister(address(), kFactoryResetRegister, 0));
}

TimedIntent Ld58a08::pwmIntent(const PwmSettings& s) const {
  TimedIntent t;
  t.channel = s.channel;
  t.after = false;
  if (s.channel < 6) {
    t.seconds = s.pulses == 0 ? -1.0 : s.pulses * s.period;
  } else {
    t.seconds = s.duration == 0.0 ? -1.0 : s.duration;
  }
  if (t.seconds < 0) t.restart = pwmWrite(s);
  return t;
}

namespace {

// The value a client's register write (FC06 / FC16) puts into `reg`, if it writes it.
std::optional<uint16_t> registerWritten(const Request& request, uint16_t reg) {
  if (request.function != FunctionCode::kWriteMultipleRegisters &&
      request.function != FunctionCode::kWriteSingleRegister)
    return {};
  if (reg < request.address || reg >= request.address + request.values.size()) return {};
  return request.values[reg - request.address];
}

}  // namespace

std::vector<TimedIntent> Ld58a08::timedWrittenBy(const Request& request) const {
  std::vector<TimedIntent> timed;
  const auto written = [&request](uint16_t reg) { return registerWritten(request, reg); };
  for (uint8_t ch = 0; ch < kChannels; ++ch) {
    const auto enable = written(pwmRegister(ch) + 2);
    if (!enable || *enable == 0) continue;  // not written, or a stop: the next poll shows it
    TimedIntent t;
    t.channel = ch;
    t.after = false;
    if (*enable == kContinuous) {
      t.seconds = -1.0;
      // Its settings written with it: a restore can start it again (not a write of the enable
      // register alone, whose settings the node may not know).
      const auto first = written(pwmRegister(ch)), second = written(pwmRegister(ch) + 1);
      if (first && second) {
        Request again =
            Request::writeMultipleRegisters(address(), pwmRegister(ch), {*first, *second, *enable});
        again.repeatable = false;
        t.restart = again;
      }
    } else if (ch < 6) {
      // Pulses of the period written with it, or of the one the board already has.
      const double period =
          written(pwmRegister(ch))
              .value_or(static_cast<uint16_t>(std::lround(pwm_[ch].period * 10))) /
          10.0;
      t.seconds = *enable * period;
    } else {
      t.seconds = *enable / 10.0;  // output time in 0.1 s
    }
    timed.push_back(t);
  }
  return timed;
}

void Ld58a08::noteCarriedWrite(const Request& request) {
  for (uint8_t ch = 0; ch < kChannels; ++ch) {
    // A stop, and a continuous run: a timed run a client started is a timed command the
    // fail-safe knows (with its end), while a snapshot that says "running" would outlive a
    // short burst until re-read; a continuous run has no end, and the snapshot says it runs
    // until a read says otherwise (docs/failsafe.md: a client's coil write does not stop it).
    const auto enable = registerWritten(request, pwmRegister(ch) + 2);
    if (enable == kContinuous) noteContinuousRun(ch);
    if (enable != uint16_t{0}) continue;
    PwmState& p = pwm_[ch];
    p.enable = 0;
    p.running = p.continuous = false;
    p.remaining_pulses = 0;
    p.remaining_time = 0.0;
  }
}

std::vector<uint8_t> Ld58a08::timedStoppedBy(const Request& request) const {
  std::vector<uint8_t> stopped;
  if (request.function != FunctionCode::kWriteMultipleRegisters &&
      request.function != FunctionCode::kWriteSingleRegister)
    return stopped;
  // Only a write of PWM registers alone is decoded per channel: anything else it wrote (the
  // outputs register, a setting) is taken from the next poll for the whole device.
  for (size_t i = 0; i < request.values.size(); ++i) {
    const size_t reg = request.address + i;
    if (reg / 0x10 >= kChannels || reg % 0x10 > 2) return stopped;
  }
  for (uint8_t ch = 0; ch < kChannels; ++ch)
    if (registerWritten(request, pwmRegister(ch) + 2) == uint16_t{0}) stopped.push_back(ch);
  return stopped;
}

}  // namespace modbus_rtu_driver
