#include "modbus_rtu_driver/devices/lc_relay8.h"

#include <cmath>
#include <cstdio>

#include "modbus_rtu_driver/core/config/number_text.h"
#include "modbus_rtu_driver/devices/registry.h"

namespace modbus_rtu_driver {

// `type: lc_relay8` in the bus YAML builds this class (devices/registry.h).
[[maybe_unused]] const bool kLcRelay8Registered =
    deviceClasses().add(kLcRelay8Type, makeDevice<LcRelay8>);

Result LcRelay8::poll(Transport& link) {
  Result relays = link.execute(Request::readCoils(address(), 0, kChannels));
  if (!relays.ok()) return relays;
  outputs_.assign(relays.values.begin(), relays.values.end());
  Result inputs = link.execute(Request::readDiscreteInputs(address(), 0, kChannels));
  if (!inputs.ok()) return inputs;
  inputs_.assign(inputs.values.begin(), inputs.values.end());
  return inputs;
}

std::string LcRelay8::pulseTenths(uint8_t channel, double duration, uint16_t* tenths) {
  if (channel >= kChannels) return "channel: " + std::to_string(channel) + " is outside 0-7";
  // Convert first (the nearest 0.1 s, float noise allowed), then check the register value that
  // would be written: 0x0001-0xFFFF.
  const double units = duration * 10.0;
  const double nearest = std::isfinite(units) ? std::round(units) : -1;
  if (nearest < 1 || nearest > 65535)
    return "duration: " + numberText(duration) + " s is outside 0.1-6553.5 s";
  if (std::fabs(units - nearest) > 1e-3 + 1e-9 * nearest)
    return "duration: " + numberText(duration) +
           " s is not a multiple of the 0.1 s step (0.1-6553.5 s in steps of 0.1 s)";
  if (tenths) *tenths = static_cast<uint16_t>(nearest);
  return {};
}

std::string LcRelay8::validatePulse(uint8_t channel, double duration) {
  return pulseTenths(channel, duration, nullptr);
}

Result LcRelay8::pulse(Transport& link, uint8_t channel, bool state, double duration) {
  uint16_t tenths = 0;
  const std::string problem = pulseTenths(channel, duration, &tenths);
  if (!problem.empty()) return Result::failure(ErrorKind::kInvalidArgument, problem);
  Request write = Request::writeMultipleRegisters(address(), flashRegister(channel),
                                                  {state ? kFlashClose : kFlashOpen, tenths});
  write.repeatable = false;  // a second copy would start the timed flash again
  Result r = link.execute(write);
  if (!r.ok() && mayHaveActed(r))
    r.message += "; not confirmed: the board may have started the flash, so it is not sent again";
  return r;
}

Result LcRelay8::readBaudCode(Transport& link, uint16_t* code) {
  Result r = link.execute(Request::readHoldingRegisters(address(), kBaudReadRegister, 1));
  if (r.ok()) *code = r.values[0];
  return r;
}

Result LcRelay8::writeBaudCode(Transport& link, uint16_t code) {
  if (code < 2 || code > 4)
    return Result::failure(
        ErrorKind::kInvalidArgument,
        "baud code: " + std::to_string(code) + " is outside 2-4 (4800, 9600, 19200 baud)");
  return link.execute(Request::writeMultipleRegisters(address(), kBaudWriteRegister, {code}));
}

Result LcRelay8::readAddressAtZero(Transport& link) {
  Request r = Request::readHoldingRegisters(kBroadcastAddress, 0, 1);
  r.single_device_at_zero = true;
  return link.execute(r);
}

Result LcRelay8::setAddressAtZero(Transport& link, uint8_t new_address) {
  if (new_address < 1)
    return Result::failure(ErrorKind::kInvalidArgument, "address: 0 is outside 1-255");
  Request r = Request::writeMultipleRegisters(kBroadcastAddress, 0, {new_address});
  r.single_device_at_zero = true;
  r.reply_echoes_request = true;
  return link.execute(r);
}

std::vector<TimedIntent> LcRelay8::timedWrittenBy(const Request& request) const {
  std::vector<TimedIntent> timed;
  if (request.function != FunctionCode::kWriteMultipleRegisters) return timed;
  for (uint8_t ch = 0; ch < kChannels; ++ch) {
    const uint16_t mode = flashRegister(ch);
    if (mode < request.address ||
        static_cast<size_t>(mode) + 1 >= request.address + request.values.size())
      continue;
    const uint16_t kind = request.values[mode - request.address];
    const uint16_t tenths = request.values[mode + 1 - request.address];
    if ((kind != kFlashClose && kind != kFlashOpen) || tenths == 0) continue;
    const bool close = kind == kFlashClose;  // closes (on) for the delay, then opens
    timed.emplace_back(ch, close, !close, tenths / 10.0);
  }
  return timed;
}

}  // namespace modbus_rtu_driver
