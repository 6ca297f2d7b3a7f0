// The commissioning tool's settings commands (get-/set-address, -baud, -parity, -return-delay,
// -save, factory-reset) and which registered types have them (devices/commissioning.h).
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "modbus_rtu_driver/devices/commissioning.h"

namespace modbus_rtu_driver::commission_args {

struct SettingCommand {
  const char* get;
  const char* set;  // null: factory-reset (no value, no get)
  BoardFeature feature;
  const char* what;   // "the stored baud rate"
  const char* value;  // the value's name in --help: "BAUD"
  const char* label;  // the value in messages: "baud"
};

// Every settings command, in the order --help lists them.
inline constexpr SettingCommand kSettingCommands[] = {
    {"get-address", "set-address", BoardFeature::kAddress, "the board's address", "NEW",
     "new address"},
    {"get-baud", "set-baud", BoardFeature::kBaud, "the stored baud rate", "BAUD", "baud"},
    {"get-parity", "set-parity", BoardFeature::kParity, "the stored parity", "none|even|odd",
     "parity"},
    {"get-return-delay", "set-return-delay", BoardFeature::kReturnDelay,
     "the wait before answering", "MS", "return delay"},
    {"get-save", "set-save", BoardFeature::kPowerDownSave,
     "the power-down save of the PWM settings", "on|off", "power-down save"},
    {"factory-reset", nullptr, BoardFeature::kFactoryReset, "factory settings", "", ""},
};

const SettingCommand* settingCommand(const std::string& command);
// The registered types that have `feature`, in probe order.
std::vector<CommissioningType> typesWith(BoardFeature feature);
std::vector<std::string> namesOf(const std::vector<CommissioningType>& types);
// "a" or "an" before a type's name, read as letters ("an ld58a08", "a yespeed_pdu").
std::string withArticle(const std::string& name);
// --type of a settings command: a registered type that has the command's feature.
CLI::Validator typeFor(const std::string& command, BoardFeature feature);
// The codes a type's baud setting takes, as rates: "4800, 9600, 19200", or "1200-115200" for
// more than three.
std::string baudsOf(const Commissioning& type, bool short_form);
// What --help says of a settings command's value and types, from the registered classes.
std::string rangeHelp(const SettingCommand& s);

}  // namespace modbus_rtu_driver::commission_args
