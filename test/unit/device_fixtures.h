// Fixtures of the device tests against a scripted transport: a device's settings by type and
// address, frames and replies as hex, an LD58A08's first poll, and the check a test ends with
// (every frame as scripted, the script used up).
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "modbus_rtu_driver/devices/device.h"
#include "scripted_transport.h"

namespace modbus_rtu_driver {
namespace devtest {

inline DeviceConfig config(const std::string& type, int address) {
  DeviceConfig c;
  c.name = "dev";
  c.type = type;
  c.address = address;
  return c;
}

// A request's frame and a device's replies, as hex for ScriptedTransport.
inline std::string frame(const Request& r) {
  return toHex(encodeRequest(r));
}
// FC01 of coils 0-7: bit i of `bits` is coil i.
inline std::string coilsReply(uint8_t slave, unsigned bits) {
  std::vector<uint16_t> values;
  for (unsigned i = 0; i < 8; ++i) values.push_back(static_cast<uint16_t>(bits >> i & 1u));
  return toHex(encodeReply(Request::readCoils(slave, 0, 8), values));
}
inline std::string registersReply(uint8_t slave, uint16_t address,
                                  const std::vector<uint16_t>& values) {
  return toHex(encodeReply(
      Request::readHoldingRegisters(slave, address, static_cast<uint16_t>(values.size())), values));
}

// An LD58A08's first poll (address 1): every channel's PWM registers (period, on time, pulses),
// `pwm(channel)`, idle when not given; then its outputs (`coils`, bit i = output i).
inline void expectFirstLd58a08Poll(
    ScriptedTransport& bus, unsigned coils = 0,
    const std::function<std::vector<uint16_t>(uint16_t)>& pwm = nullptr) {
  for (uint16_t ch = 0; ch < 8; ++ch) {
    const auto address = static_cast<uint16_t>(ch * 0x10);
    bus.expect(frame(Request::readHoldingRegisters(1, address, 3)),
               registersReply(1, address, pwm ? pwm(ch) : std::vector<uint16_t>{0, 0, 0}));
  }
  bus.expect(frame(Request::readCoils(1, 0, 8)), coilsReply(1, coils));  // after the registers
}

}  // namespace devtest
}  // namespace modbus_rtu_driver

#define EXPECT_SCRIPT_DONE(bus)        \
  do {                                 \
    EXPECT_EQ((bus).mismatches(), ""); \
    EXPECT_TRUE((bus).usedUp());       \
  } while (0)
