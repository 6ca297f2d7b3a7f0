#include "modbus_rtu_driver/sim/sim_lc_relay8.h"

#include <yaml-cpp/yaml.h>

#include "modbus_rtu_driver/sim/simulator.h"

namespace modbus_rtu_driver {

// `type: lc_relay8` in the simulator's file builds this class (sim/simulator.h).
[[maybe_unused]] const bool kSimLcRelay8Registered =
    simDeviceClasses().add(kLcRelay8Type, makeSimDeviceOf<SimLcRelay8>);

namespace {

constexpr uint16_t kFlashClose = 0x0004, kFlashOpen = 0x0002;
constexpr uint16_t kBaudRead = 0x03E8, kBaudWrite = 0x03E9;

int baudOfCode(uint16_t code) {
  return code == 2 ? 4800 : code == 4 ? 19200 : 9600;
}
// Register 0x0003 + 5*n: relay n's flash mode, the next one its delay.
bool isFlashRegister(uint32_t a) {
  return a >= 3 && a < 3 + 5 * 8 && (a - 3) % 5 <= 1;
}

}  // namespace

SimLcRelay8::SimLcRelay8(uint8_t address, SimLineSettings line) : SimDevice(address, line) {
  baud_code_ = line.baud == 4800 ? 2 : line.baud == 19200 ? 4 : 3;
}

bool SimLcRelay8::isAddressCommand(const Request& r) {
  return r.slave == kBroadcastAddress && r.address == 0 && r.count == 1 &&
         (r.function == FunctionCode::kReadHoldingRegisters ||
          r.function == FunctionCode::kWriteMultipleRegisters);
}

std::optional<Bytes> SimLcRelay8::handleBroadcast(const Request& r, SimClock::time_point now) {
  if (!isAddressCommand(r)) return SimDevice::handleBroadcast(r, now);
  if (r.function == FunctionCode::kReadHoldingRegisters) return encodeReply(r, {address_});
  if (r.values[0] < 1 || r.values[0] > 255)
    return encodeException(0, static_cast<uint8_t>(r.function), kIllegalDataValue);
  address_ = static_cast<uint8_t>(r.values[0]);  // answers at the new address from now on
  Request echo = r;
  echo.reply_echoes_request = true;  // the board echoes the whole request (manual)
  return encodeReply(echo, {});
}

void SimLcRelay8::setRelay(uint8_t ch, bool on) {
  const uint8_t bit = static_cast<uint8_t>(1u << ch);
  relays_ = on ? (relays_ | bit) : (relays_ & static_cast<uint8_t>(~bit));
}

void SimLcRelay8::tick(SimClock::time_point now) {
  for (uint8_t ch = 0; ch < 8; ++ch) {
    Flash& f = flash_[ch];
    if (!f.active || now < f.ends) continue;
    f.active = false;
    setRelay(ch, f.mode != kFlashClose);  // flash-close ends open, flash-open ends closed
  }
}

uint8_t SimLcRelay8::read(Table table, uint16_t a, SimClock::time_point now, uint16_t* v) {
  tick(now);
  switch (table) {
    case Table::kCoil:
      if (a > 7) return kIllegalDataAddress;
      *v = (relays_ >> a) & 1;
      return 0;
    case Table::kDiscreteInput:
      if (a > 7) return kIllegalDataAddress;
      *v = (inputs_ >> a) & 1;
      return 0;
    case Table::kHoldingRegister:
      if (a == kBaudRead) {
        *v = baud_code_;
        return 0;
      }
      if (isFlashRegister(a)) {
        const Flash& f = flash_[(a - 3) / 5];
        *v = (a - 3) % 5 == 0 ? f.mode : f.delay;
        return 0;
      }
      return kIllegalDataAddress;
    default:
      return kIllegalFunction;  // no input registers
  }
}

bool SimLcRelay8::startsSomething(const Request& r) const {
  return r.function == FunctionCode::kWriteMultipleRegisters && r.address >= 3 &&
         r.address < 3 + 5 * 8 && (r.address - 3) % 5 == 0;
}

uint8_t SimLcRelay8::write(Table table, uint16_t a, const std::vector<uint16_t>& values,
                           SimClock::time_point now) {
  tick(now);
  if (table == Table::kCoil) {
    if (a + values.size() > 8) return kIllegalDataAddress;
    for (size_t i = 0; i < values.size(); ++i) {
      const uint8_t ch = static_cast<uint8_t>(a + i);
      setRelay(ch, values[i] != 0);
      flash_[ch].active = false;  // manual mode cancels a running flash
    }
    return 0;
  }
  if (table != Table::kHoldingRegister) return kIllegalFunction;
  if (a == kBaudWrite && values.size() == 1) {
    if (values[0] < 2 || values[0] > 4) return kIllegalDataValue;  // 4800, 9600, 19200
    baud_code_ = values[0];
    baud_code_written_ = true;
    return 0;
  }
  // A flash: mode and delay together at 0x0003 + 5*n.
  if (a >= 3 && a < 3 + 5 * 8 && (a - 3) % 5 == 0 && values.size() == 2) {
    const uint16_t mode = values[0], delay = values[1];
    if ((mode != kFlashClose && mode != kFlashOpen) || delay == 0) return kIllegalDataValue;
    const uint8_t ch = static_cast<uint8_t>((a - 3) / 5);
    Flash& f = flash_[ch];
    f.mode = mode;
    f.delay = delay;
    f.active = true;
    f.ends = now + std::chrono::milliseconds(100 * delay);
    setRelay(ch, mode == kFlashClose);
    return 0;
  }
  return kIllegalDataAddress;
}

uint8_t SimLcRelay8::setDirect(Table table, uint16_t a, uint16_t v, SimClock::time_point now) {
  if (table != Table::kDiscreteInput) return SimDevice::setDirect(table, a, v, now);
  if (a > 7) return kIllegalDataAddress;
  const uint8_t bit = static_cast<uint8_t>(1u << a);
  inputs_ = v ? (inputs_ | bit) : (inputs_ & static_cast<uint8_t>(~bit));
  return 0;
}

void SimLcRelay8::powerCycle(SimClock::time_point) {
  // The board takes its stored baud code at power-on. One the simulator was told to put on a line
  // its codes cannot express (they are 4800, 9600 and 19200: a real board would never answer
  // there) keeps that line until a code is written to it, rather than falling silent for good at
  // its first power cycle (docs/simulator.md).
  const bool coded_line = line_.baud == 4800 || line_.baud == 9600 || line_.baud == 19200;
  if (coded_line || baud_code_written_) line_.baud = baudOfCode(baud_code_);
  relays_ = 0;
  flash_ = {};
}

void SimLcRelay8::saveState(YAML::Node& n) const {
  n["address"] = static_cast<int>(address_);
  n["baud_code"] = baud_code_;
  n["baud"] = line_.baud;
}

void SimLcRelay8::loadState(const YAML::Node& n, SimClock::time_point) {
  const int address = n["address"].as<int>(address_);
  if (address >= 1 && address <= 255) address_ = static_cast<uint8_t>(address);
  const uint16_t code = n["baud_code"].as<uint16_t>(baud_code_);
  if (code >= 2 && code <= 4) baud_code_ = code;
  line_.baud = n["baud"].as<int>(line_.baud);
}

}  // namespace modbus_rtu_driver
