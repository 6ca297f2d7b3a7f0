#include "modbus_rtu_driver/core/modbus/types.h"

#include <cstdio>

namespace modbus_rtu_driver {

bool isKnownFunction(uint8_t code) {
  switch (code) {
    case 0x01:
    case 0x02:
    case 0x03:
    case 0x04:
    case 0x05:
    case 0x06:
    case 0x0F:
    case 0x10:
      return true;
    default:
      return false;
  }
}

bool isReadFunction(FunctionCode fc) {
  return static_cast<uint8_t>(fc) <= 0x04;
}

Table tableOf(FunctionCode fc) {
  switch (fc) {
    case FunctionCode::kReadCoils:
    case FunctionCode::kWriteSingleCoil:
    case FunctionCode::kWriteMultipleCoils:
      return Table::kCoil;
    case FunctionCode::kReadDiscreteInputs:
      return Table::kDiscreteInput;
    case FunctionCode::kReadInputRegisters:
      return Table::kInputRegister;
    case FunctionCode::kReadHoldingRegisters:
    case FunctionCode::kWriteSingleRegister:
    case FunctionCode::kWriteMultipleRegisters:
      break;
  }
  return Table::kHoldingRegister;
}

uint16_t maxCount(FunctionCode fc) {
  switch (fc) {
    case FunctionCode::kReadCoils:
    case FunctionCode::kReadDiscreteInputs:
      return kMaxReadBits;
    case FunctionCode::kReadHoldingRegisters:
    case FunctionCode::kReadInputRegisters:
      return kMaxReadRegisters;
    case FunctionCode::kWriteMultipleCoils:
      return kMaxWriteBits;
    case FunctionCode::kWriteMultipleRegisters:
      return kMaxWriteRegisters;
    case FunctionCode::kWriteSingleCoil:
    case FunctionCode::kWriteSingleRegister:
      break;
  }
  return 1;
}

const char* tableName(Table table) {
  return nameIn(kTableNames, table).data();  // the table's names are literals: terminated
}

bool isBitTable(Table table) {
  return table == Table::kCoil || table == Table::kDiscreteInput;
}

std::optional<Table> formerTableName(std::string_view name) {
  // Spellings earlier versions took here and there; refused, but pointed at the one name.
  // ("input" is not among them: it meant discrete inputs in one place, input registers in another.)
  static constexpr NameTable<Table, 9> kFormerNames{{{Table::kCoil, "coils"},
                                                     {Table::kDiscreteInput, "discrete_inputs"},
                                                     {Table::kDiscreteInput, "discrete-inputs"},
                                                     {Table::kDiscreteInput, "discrete"},
                                                     {Table::kHoldingRegister, "holding_registers"},
                                                     {Table::kHoldingRegister, "holding"},
                                                     {Table::kInputRegister, "input_registers"},
                                                     {Table::kInputRegister, "input-registers"},
                                                     {Table::kInputRegister, "ireg"}}};
  return valueIn(kFormerNames, name);
}

std::optional<Table> parseTableName(std::string_view name, std::string* error) {
  if (auto table = valueIn(kTableNames, name)) return table;
  if (error) {
    *error = "'" + std::string(name) + "' is not one of " + namesIn(kTableNames);
    if (auto former = formerTableName(name))
      *error += " (the table is now named '" + std::string(tableName(*former)) + "')";
  }
  return std::nullopt;
}

bool isBitFunction(FunctionCode fc) {
  return fc == FunctionCode::kReadCoils || fc == FunctionCode::kReadDiscreteInputs ||
         fc == FunctionCode::kWriteSingleCoil || fc == FunctionCode::kWriteMultipleCoils;
}

const char* functionName(FunctionCode fc) {
  // The Modbus specification's names of the functions this driver speaks.
  static constexpr NameTable<FunctionCode, 8> kFunctionNames{
      {{FunctionCode::kReadCoils, "read coils"},
       {FunctionCode::kReadDiscreteInputs, "read discrete inputs"},
       {FunctionCode::kReadHoldingRegisters, "read holding registers"},
       {FunctionCode::kReadInputRegisters, "read input registers"},
       {FunctionCode::kWriteSingleCoil, "write single coil"},
       {FunctionCode::kWriteSingleRegister, "write single register"},
       {FunctionCode::kWriteMultipleCoils, "write multiple coils"},
       {FunctionCode::kWriteMultipleRegisters, "write multiple registers"}}};
  const std::string_view name = nameIn(kFunctionNames, fc);  // "?" when not in the table
  return name == "?" ? "unknown function" : name.data();     // literals: terminated
}

std::string exceptionName(uint8_t code) {
  switch (code) {
    case kIllegalFunction:
      return "illegal function (01)";
    case kIllegalDataAddress:
      return "illegal data address (02)";
    case kIllegalDataValue:
      return "illegal data value (03)";
    case kSlaveDeviceFailure:
      return "slave device failure (04)";
    case kSlaveDeviceBusy:
      return "slave device busy (06)";
    case kGatewayPathUnavailable:
      return "gateway path unavailable (0A)";
    case kGatewayTargetFailed:
      return "gateway target device failed to respond (0B)";
    default: {
      char buf[40];
      std::snprintf(buf, sizeof buf, "exception %02X", code);
      return buf;
    }
  }
}

namespace {
Request make(uint8_t slave, FunctionCode fc, uint16_t address, uint16_t count) {
  Request r;
  r.slave = slave;
  r.function = fc;
  r.address = address;
  r.count = count;
  return r;
}
}  // namespace

Request Request::read(uint8_t s, Table table, uint16_t a, uint16_t n) {
  switch (table) {
    case Table::kCoil:
      return readCoils(s, a, n);
    case Table::kDiscreteInput:
      return readDiscreteInputs(s, a, n);
    case Table::kHoldingRegister:
      return readHoldingRegisters(s, a, n);
    case Table::kInputRegister:
      break;
  }
  return readInputRegisters(s, a, n);
}

Request Request::readCoils(uint8_t s, uint16_t a, uint16_t n) {
  return make(s, FunctionCode::kReadCoils, a, n);
}
Request Request::readDiscreteInputs(uint8_t s, uint16_t a, uint16_t n) {
  return make(s, FunctionCode::kReadDiscreteInputs, a, n);
}
Request Request::readHoldingRegisters(uint8_t s, uint16_t a, uint16_t n) {
  return make(s, FunctionCode::kReadHoldingRegisters, a, n);
}
Request Request::readInputRegisters(uint8_t s, uint16_t a, uint16_t n) {
  return make(s, FunctionCode::kReadInputRegisters, a, n);
}
Request Request::writeSingleCoil(uint8_t s, uint16_t a, bool on) {
  Request r = make(s, FunctionCode::kWriteSingleCoil, a, 1);
  r.values = {static_cast<uint16_t>(on ? 1 : 0)};
  return r;
}
Request Request::writeSingleRegister(uint8_t s, uint16_t a, uint16_t v) {
  Request r = make(s, FunctionCode::kWriteSingleRegister, a, 1);
  r.values = {v};
  return r;
}
Request Request::writeMultipleCoils(uint8_t s, uint16_t a, const std::vector<bool>& bits) {
  Request r = make(s, FunctionCode::kWriteMultipleCoils, a, static_cast<uint16_t>(bits.size()));
  for (bool b : bits) r.values.push_back(b ? 1 : 0);
  return r;
}
Request Request::writeMultipleRegisters(uint8_t s, uint16_t a, const std::vector<uint16_t>& v) {
  Request r = make(s, FunctionCode::kWriteMultipleRegisters, a, static_cast<uint16_t>(v.size()));
  r.values = v;
  return r;
}

std::string Request::validate() const {
  if (!isKnownFunction(static_cast<uint8_t>(function))) return "function: unsupported code";
  if (slave == kBroadcastAddress && isReadFunction(function) && !single_device_at_zero)
    return "slave: 0 (broadcast) is only allowed for writes";
  const uint16_t max = maxCount(function);
  if (count < 1 || count > max)
    return "count: " + std::to_string(count) + " is outside 1-" + std::to_string(max);
  if (static_cast<uint32_t>(address) + count > 0x10000u)
    return "address: range " + std::to_string(address) + "+" + std::to_string(count) +
           " passes 65535";
  if (!isReadFunction(function)) {
    if (values.size() != count)
      return "values: " + std::to_string(values.size()) + " given for count " +
             std::to_string(count);
    if (isBitFunction(function))
      for (uint16_t v : values)
        if (v > 1) return "values: coil states must be 0 or 1";
  }
  return {};
}

std::string Request::describe() const {
  char buf[128];
  std::snprintf(buf, sizeof buf, "FC%02X %s, slave %u, address 0x%04X, count %u",
                static_cast<unsigned>(function), functionName(function),
                static_cast<unsigned>(slave), static_cast<unsigned>(address),
                static_cast<unsigned>(count));
  return buf;
}

Result Result::success(std::vector<uint16_t> values) {
  Result r;
  r.values = std::move(values);
  return r;
}

Result Result::failure(ErrorKind kind, std::string message, uint8_t exception_code) {
  Result r;
  r.error = kind;
  r.message = std::move(message);
  r.exception_code = exception_code;
  return r;
}

Request forwarded(Request request) {
  request.repeatable = isReadFunction(request.function);
  return request;
}

}  // namespace modbus_rtu_driver
