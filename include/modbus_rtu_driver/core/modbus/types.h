// Plain Modbus request/result types shared by the bus, the devices and the simulator.
// ROS-free: nothing here may include ros.h.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "modbus_rtu_driver/core/modbus/text.h"

namespace modbus_rtu_driver {

// The four Modbus tables, with one name each wherever users name one: signals' `table`, the
// slave role's table sizes and names, the simulator's get/set, the commissioning tool's --table.
enum class Table { kCoil, kDiscreteInput, kHoldingRegister, kInputRegister };
inline constexpr NameTable<Table, 4> kTableNames{{{Table::kCoil, "coil"},
                                                  {Table::kDiscreteInput, "discrete_input"},
                                                  {Table::kHoldingRegister, "holding_register"},
                                                  {Table::kInputRegister, "input_register"}}};
const char* tableName(Table table);
bool isBitTable(Table table);  // coils and discrete inputs
// A table by its name; otherwise nullopt and `error` says what the names are, with a hint when
// `name` is one of the spellings earlier versions took ("holding", "coils", "input-registers").
std::optional<Table> parseTableName(std::string_view name, std::string* error);
// The table a spelling of earlier versions meant ("holding_registers" -> holding_register).
std::optional<Table> formerTableName(std::string_view name);

enum class FunctionCode : uint8_t {
  kReadCoils = 0x01,
  kReadDiscreteInputs = 0x02,
  kReadHoldingRegisters = 0x03,
  kReadInputRegisters = 0x04,
  kWriteSingleCoil = 0x05,
  kWriteSingleRegister = 0x06,
  kWriteMultipleCoils = 0x0F,
  kWriteMultipleRegisters = 0x10,
};

bool isKnownFunction(uint8_t code);
bool isReadFunction(FunctionCode fc);
bool isBitFunction(FunctionCode fc);  // 01, 02, 05, 15
const char* functionName(FunctionCode fc);

// Modbus exception codes (the ones a device sends back in an exception reply).
enum ExceptionCode : uint8_t {
  kIllegalFunction = 0x01,
  kIllegalDataAddress = 0x02,
  kIllegalDataValue = 0x03,
  kSlaveDeviceFailure = 0x04,
  kSlaveDeviceBusy = 0x06,
  kGatewayPathUnavailable = 0x0A,  // a gateway's answers (the node's share): the bus is not open
  kGatewayTargetFailed = 0x0B,     // the device behind the gateway did not answer (properly)
};
std::string exceptionName(uint8_t code);

constexpr uint8_t kBroadcastAddress = 0;
constexpr uint8_t kMaxStandardSlave =
    247;  // 248-255 are reserved by the spec but used by real boards
constexpr size_t kMaxAduLength = 256;
constexpr uint16_t kMaxReadBits = 2000;
constexpr uint16_t kMaxReadRegisters = 125;
constexpr uint16_t kMaxWriteBits = 1968;
constexpr uint16_t kMaxWriteRegisters = 123;
// The table a function reads or writes (FC05 and FC15 write coils, FC06 and FC16 holding
// registers), and the most items one request of it may carry (the limits above; 1 for FC05 and
// FC06): one definition for the client's checks, the slave role and the simulator.
Table tableOf(FunctionCode fc);
uint16_t maxCount(FunctionCode fc);

// One Modbus transaction as the caller means it. For bit functions, `values` holds 0/1.
struct Request {
  uint8_t slave = 1;
  FunctionCode function = FunctionCode::kReadHoldingRegisters;
  uint16_t address = 0;
  uint16_t count = 1;            // items to read or write (1 for 05/06)
  std::vector<uint16_t> values;  // write payload
  // Address 0 is a broadcast: nobody answers. Some boards (LC relay) answer commands sent to
  // address 0 when they are alone on the bus; such requests set this flag.
  bool single_device_at_zero = false;
  // The LC board answers its FC16 "set address" command by echoing the whole request.
  bool reply_echoes_request = false;
  // False for a write that starts something (a PWM burst, a timed flash): sent once, never
  // retried after a lost reply, since the device may have acted on it (the caller reads back).
  bool repeatable = true;

  // The read of `table` (FC01-FC04).
  static Request read(uint8_t slave, Table table, uint16_t address, uint16_t count);
  static Request readCoils(uint8_t slave, uint16_t address, uint16_t count);
  static Request readDiscreteInputs(uint8_t slave, uint16_t address, uint16_t count);
  static Request readHoldingRegisters(uint8_t slave, uint16_t address, uint16_t count);
  static Request readInputRegisters(uint8_t slave, uint16_t address, uint16_t count);
  static Request writeSingleCoil(uint8_t slave, uint16_t address, bool on);
  static Request writeSingleRegister(uint8_t slave, uint16_t address, uint16_t value);
  static Request writeMultipleCoils(uint8_t slave, uint16_t address, const std::vector<bool>& bits);
  static Request writeMultipleRegisters(uint8_t slave, uint16_t address,
                                        const std::vector<uint16_t>& values);

  bool expectsReply() const { return slave != kBroadcastAddress || single_device_at_zero; }
  // Empty when the request is well formed, else a message naming the bad field.
  std::string validate() const;
  // "FC03 read holding registers, slave 1, address 0x00FD, count 1"
  std::string describe() const;
};

// A request the node carries for someone else (a share client, the raw write services): a write
// is sent once (not repeatable), since the node cannot tell whether it starts something (an LC
// flash, an LD58A08 burst); the caller decides on a retry. Reads stay repeatable.
Request forwarded(Request request);

enum class ErrorKind {
  kNone,
  kTimeout,          // no (complete) reply in time
  kCrc,              // a reply arrived with a bad CRC
  kWrongAddress,     // a reply from another slave
  kException,        // the device answered with a Modbus exception
  kMalformed,        // a reply that does not fit the request
  kIo,               // the port failed (unplugged, closed)
  kInvalidArgument,  // refused before anything reached the bus
  kNotConnected,     // the port is not open
};

// How the kinds of failure are told apart, in one place:
// the request reached the device and its answer was lost or garbled: a retry may help, and a
// write may have been done (read back before reporting it failed);
inline bool answerLost(ErrorKind k) {
  return k == ErrorKind::kTimeout || k == ErrorKind::kCrc || k == ErrorKind::kWrongAddress ||
         k == ErrorKind::kMalformed;
}
// the request may have been carried out though it failed: its answer lost, or the port failed
// after it may have gone out (kIo); the fail-safe takes such a write's channels as found;
inline bool outcomeUnknown(ErrorKind k) {
  return answerLost(k) || k == ErrorKind::kIo;
}
// the device did not answer properly, or could not be asked: counts towards "offline" (an
// exception is an answer).
inline bool noProperAnswer(ErrorKind k) {
  return answerLost(k) || k == ErrorKind::kIo || k == ErrorKind::kNotConnected;
}

// Outcome of one transaction. `values` carries what was read (bits as 0/1) or, for writes,
// what the device confirmed.
struct Result {
  ErrorKind error = ErrorKind::kNone;
  uint8_t exception_code = 0;
  std::string message;
  std::vector<uint16_t> values;
  // The answer was lost and the retries the link would have made are left for a later call
  // (Transport::executeAttempts: a shared read cut short in another device's late-reply guard).
  bool retry_owed = false;

  bool ok() const { return error == ErrorKind::kNone; }
  static Result success(std::vector<uint16_t> values = {});
  static Result failure(ErrorKind kind, std::string message, uint8_t exception_code = 0);
};

}  // namespace modbus_rtu_driver
