#include "modbus_rtu_driver/runtime/device_unit.h"

#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/devices/generic_device.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/devices/yespeed_pdu.h"

namespace modbus_rtu_driver {

DeviceUnit::DeviceUnit(std::shared_ptr<Device> device, BusScheduler& scheduler, Clock& clock)
    : device_(std::move(device)),
      scheduler_(scheduler),
      failsafe_(*device_, scheduler, clock),
      commands_(*device_, failsafe_, scheduler) {
  if (GenericDevice* g = generic())
    generic_safe_ = std::make_unique<GenericFailsafe>(*g, scheduler);
  failsafe_.setReportSink([this](const FailsafeReport& r) {
    if (observers_.report) observers_.report(r, r.text());
  });
  failsafe_.setOutputsWritten([this] { changed(); });
  commands_.setWritten(
      [this](const std::vector<uint8_t>& channels, const std::vector<bool>& states) {
        if (observers_.written) observers_.written(channels, states);
        changed();
      });
  if (generic_safe_) {
    generic_safe_->setReportSink([this](const FailsafeReport& r) {
      if (observers_.report) observers_.report(r, generic_safe_->text(r));
    });
    generic_safe_->setSignalsWritten([this] { changed(); });
  }
}

GenericDevice* DeviceUnit::generic() const {
  return dynamic_cast<GenericDevice*>(device_.get());
}

std::future<Result> DeviceUnit::refuse(const std::string& problem) const {
  return readyResult(Result::failure(ErrorKind::kInvalidArgument, problem));
}

// ---- fail-safe --------------------------------------------------------------------------------

std::future<Result> DeviceUnit::applySafe(Trigger trigger, const std::string& reason,
                                          const std::vector<uint8_t>& only) {
  // A generic device's safe values stand for the outputs' safe states (it has no outputs).
  if (generic_safe_) return generic_safe_->applySafe(trigger, reason);
  return failsafe_.applySafe(trigger, reason, only);
}

bool DeviceUnit::hasSafeStates() const {
  return generic_safe_ ? generic_safe_->hasSafeValues() : failsafe_.hasSafeStates();
}

void DeviceUnit::checkDeadlines() {
  for (const auto& f : failsafe_.firedTriggers()) applySafe(f.trigger, f.reason, f.only);
}

// A node killed during a flash (or restarted by roslaunch's respawn) must not take the flash's
// end for a restart: the running timed commands are kept where the next node finds them, with
// their ends in the store's seconds, and it resumes them before its first poll.
std::string DeviceUnit::keepTimedIn(KeptTimedStore& store) {
  if (device_->outputCount() == 0) return {};
  const std::vector<TimedIntent> running =
      resumeTimedCommands(store.read(name()), store.seconds(), device_->outputCount());
  std::string told;
  for (const TimedIntent& t : running)
    told += (told.empty() ? "" : ", ") + device_->outputNames()[t.channel] + " (" +
            secondsText(t.seconds) + " left)";  // only commands with an end are kept
  if (!running.empty()) failsafe_.resumeTimed(running);
  // From the thread that confirmed the command (the bus thread), only while a timed command
  // runs or just stopped running, also for the stop's safe writes.
  failsafe_.setTimedChanged([this, &store](const std::vector<TimedIntent>& now_running) {
    if (keeping_) store.keep(name(), keepTimedCommands(now_running, store.seconds()));
  });
  return told;
}

void DeviceUnit::addPolls() {
  if (GenericDevice* g = generic()) {
    // One poll per rate group with signals in it: fast values do not drag slow ones along.
    for (size_t group = 0; group < g->groups().size(); ++group) {
      if (g->groups()[group].signals.empty()) continue;
      scheduler_.addPoll(
          name(), g->groups()[group].rate,
          [this, g, group](Transport& t) {
            if (observers_.poll_starting) observers_.poll_starting();
            return g->pollGroup(t, group);
          },
          [this, group](const Result& r) {
            generic_safe_->afterPoll(r);  // safe values owed are written once it answers
            if (observers_.polled) observers_.polled(group, r);
          });
    }
    return;
  }
  scheduler_.addPoll(
      name(), device_->config().poll_rate,
      [this](Transport& t) {
        if (observers_.poll_starting) observers_.poll_starting();
        failsafe_.pollStarting();
        return device_->poll(t);
      },
      [this](const Result& r) {
        if (r.ok())
          failsafe_.afterPoll();
        else
          failsafe_.afterFailedPoll();
        if (observers_.polled) observers_.polled(0, r);
      });
}

// ---- commands ---------------------------------------------------------------------------------

std::future<Result> DeviceUnit::set(const std::vector<uint8_t>& channels,
                                    const std::vector<bool>& states, Call call) {
  return commands_.write(channels, states, std::move(call));
}

std::future<Result> DeviceUnit::command(uint8_t channel, bool state, Call call) {
  return commands_.command(channel, state, std::move(call));
}

std::future<Result> DeviceUnit::pulse(uint8_t channel, bool state, double seconds, Call call) {
  auto* board = dynamic_cast<LcRelay8*>(device_.get());
  if (!board) return refuse("pulse: a " + device_->config().type + " has no flash");
  const std::string problem = LcRelay8::validatePulse(channel, seconds);
  if (!problem.empty()) return refuse(problem);
  // Flash-close: on for `seconds`, then off by itself; flash-open the other way round.
  return commands_.timed(
      TimedIntent{channel, state, !state, seconds},
      [board, channel, state, seconds](Transport& t) {
        return board->pulse(t, channel, state, seconds);
      },
      // The board changed the output by itself: read it back so the topics show it now.
      [this, board](Transport& t) {
        if (board->poll(t).ok()) changed();
      },
      std::move(call));
}

std::future<Result> DeviceUnit::setPwm(const PwmSettings& settings, Call call) {
  auto* board = dynamic_cast<Ld58a08*>(device_.get());
  if (!board) return refuse("set_pwm: a " + device_->config().type + " has no PWM");
  const std::string problem = Ld58a08::validatePwm(settings);
  if (!problem.empty()) return refuse(problem);
  // The PWM drives the output from now on: for a burst or a timed run until its end, then off;
  // a continuous run until stopped.
  return commands_.timed(
      board->pwmIntent(settings),
      [board, settings](Transport& t) { return board->setPwm(t, settings); },
      [this, board](Transport& t) {
        if (board->readPwm(t).ok()) changed();
      },
      std::move(call));
}

std::future<Result> DeviceUnit::stopPwm(uint8_t channel, Call call) {
  auto* board = dynamic_cast<Ld58a08*>(device_.get());
  if (!board) return refuse("stop_pwm: a " + device_->config().type + " has no PWM");
  if (channel >= Ld58a08::kChannels)
    return refuse("channel: " + std::to_string(channel) + " is outside 0-" +
                  std::to_string(Ld58a08::kChannels - 1));
  return commands_.stopTimed(
      channel, [board, channel](Transport& t) { return board->stopPwm(t, channel); },
      [this, board](Transport& t) {
        if (board->readPwm(t).ok()) changed();
      },
      std::move(call));
}

std::future<Result> DeviceUnit::setPduLimits(double over_voltage, double under_voltage,
                                             double over_current, Call call) {
  auto* pdu = dynamic_cast<YespeedPdu*>(device_.get());
  if (!pdu) return refuse("set_limits: a " + device_->config().type + " has no limits");
  const double given[3] = {over_voltage, under_voltage, over_current};
  PduLimitChange change;
  for (size_t i = 0; i < 3; ++i) {
    if (given[i] == 0.0) continue;
    uint16_t reg = 0;
    const std::string problem = YespeedPdu::limitToRegister(i, given[i], &reg);
    if (!problem.empty()) return refuse(problem);
    change[i] = reg;
  }
  if (!change[0] && !change[1] && !change[2])
    return refuse("no limit given (over_voltage, under_voltage, over_current; 0 keeps one)");
  if (change[0] && change[1] && change[2]) {  // all three: the rules before the bus is asked
    // The three given registers (merged over zeros, none of which is left).
    const std::string problem =
        YespeedPdu::checkLimitRegisters(YespeedPdu::mergeLimits(PduLimitRegisters{}, change));
    if (!problem.empty()) return refuse(problem);
  }
  return scheduler_.submit(
      name(),
      [this, pdu, change, done = std::move(call.done)](Transport& t) {
        Result w = pdu->changeLimits(t, change);
        changed();  // whatever was read is what the device holds
        if (done) done(w);
        return w;
      },
      call.tag);
}

std::future<Result> DeviceUnit::writeSignal(size_t signal, double value, Call call) {
  GenericDevice* g = generic();
  if (!g) return refuse("set: a " + device_->config().type + " has no signals");
  std::vector<uint16_t> words;
  const std::string problem = g->encodeWrite(signal, value, &words);
  if (!problem.empty()) return refuse(problem);
  GenericFailsafe& safe = *generic_safe_;  // it knows which safe values a newer set replaces
  return scheduler_.submit(
      name(),
      [this, &safe, signal, value, done = std::move(call.done)](Transport& t) {
        Result r = safe.write(t, signal, value);
        changed();
        if (done) done(r);
        return r;
      },
      call.tag);
}

}  // namespace modbus_rtu_driver
