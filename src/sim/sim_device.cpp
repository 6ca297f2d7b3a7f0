#include "modbus_rtu_driver/sim/sim_device.h"

namespace modbus_rtu_driver {

int simBitsPerCharacter(const SimLineSettings& l) {
  return 1 + l.data_bits + (l.parity == Parity::kNone ? 0 : 1) + l.stop_bits;
}

double simCharacterTime(const SimLineSettings& l) {
  return characterTime(l.baud, simBitsPerCharacter(l));
}

double simFrameGap(const SimLineSettings& l) {
  return frameGap(l.baud, simBitsPerCharacter(l));
}

std::optional<Bytes> SimDevice::handle(const Request& r, SimClock::time_point now) {
  const bool broadcast = r.slave == kBroadcastAddress;
  uint8_t exception = 0;
  std::vector<uint16_t> values;
  const bool changed = !isReadFunction(r.function) && wouldChange(r, now);
  switch (r.function) {
    case FunctionCode::kReadCoils:
    case FunctionCode::kReadDiscreteInputs:
    case FunctionCode::kReadHoldingRegisters:
    case FunctionCode::kReadInputRegisters: {
      if (broadcast) return std::nullopt;  // a read cannot be broadcast
      const uint16_t max = readLimit(isBitFunction(r.function));
      if (r.count < 1 || r.count > max) {
        exception = kIllegalDataValue;
        break;
      }
      for (uint32_t a = r.address; a < r.address + r.count && !exception; ++a) {
        uint16_t v = 0;
        exception = a > 0xFFFF ? static_cast<uint8_t>(kIllegalDataAddress)
                               : read(tableOf(r.function), static_cast<uint16_t>(a), now, &v);
        values.push_back(v);
      }
      break;
    }
    case FunctionCode::kWriteSingleCoil:
    case FunctionCode::kWriteMultipleCoils:
      if (r.values.empty() || r.values.size() > maxCount(r.function)) exception = kIllegalDataValue;
      for (uint16_t v : r.values)
        if (v > 1) exception = kIllegalDataValue;  // FC05 value not FF00/0000
      if (!exception) exception = write(Table::kCoil, r.address, r.values, now);
      break;
    case FunctionCode::kWriteSingleRegister:
    case FunctionCode::kWriteMultipleRegisters:
      if (r.values.empty() || r.values.size() > maxCount(r.function)) exception = kIllegalDataValue;
      if (!exception) exception = write(Table::kHoldingRegister, r.address, r.values, now);
      break;
  }
  if (!exception && !isReadFunction(r.function) && (changed || startsSomething(r))) ++changes;
  if (broadcast) return std::nullopt;  // applied, never answered
  if (exception) return encodeException(r.slave, static_cast<uint8_t>(r.function), exception);
  return encodeReply(r, values);
}

// True when a write would leave a coil or register other than it is now (counted in `changes`).
bool SimDevice::wouldChange(const Request& r, SimClock::time_point now) {
  const Table table = tableOf(r.function);
  for (size_t i = 0; i < r.values.size(); ++i) {
    uint16_t v = 0;
    const uint32_t a = r.address + i;
    if (a > 0xFFFF || read(table, static_cast<uint16_t>(a), now, &v) != 0 || v != r.values[i])
      return true;
  }
  return false;
}

Bytes SimDevice::unknownFunction(uint8_t slave, uint8_t function) const {
  return encodeException(slave, function, kIllegalFunction);
}

uint8_t SimDevice::setDirect(Table table, uint16_t address, uint16_t value,
                             SimClock::time_point now) {
  if (table == Table::kCoil || table == Table::kHoldingRegister)
    return write(table, address, {value}, now);
  return kIllegalDataAddress;
}

}  // namespace modbus_rtu_driver
