#include "modbus_rtu_driver/tools/commission_settings.h"

#include <functional>

#include "modbus_rtu_driver/core/config/link_config.h"
#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/tools/commission_values.h"

namespace modbus_rtu_driver::commission_args {

const SettingCommand* settingCommand(const std::string& command) {
  for (const SettingCommand& s : kSettingCommands)
    if (command == s.get || (s.set && command == s.set)) return &s;
  return nullptr;
}

// The registered types that have `feature`, in probe order.
std::vector<CommissioningType> typesWith(BoardFeature feature) {
  std::vector<CommissioningType> out;
  for (const CommissioningType& t : commissioningTypes())
    if (t.commissioning->has(feature)) out.push_back(t);
  return out;
}

std::vector<std::string> namesOf(const std::vector<CommissioningType>& types) {
  std::vector<std::string> names;
  names.reserve(types.size());
  for (const auto& t : types) names.emplace_back(t.type->name);
  return names;
}

// "a" or "an" before a type's name, read as letters ("an ld58a08", "a yespeed_pdu").
std::string withArticle(const std::string& name) {
  const std::string vowel_sounds = "aefhilmnorsx";
  const bool an = !name.empty() && vowel_sounds.find(name[0]) != std::string::npos;
  return (an ? "an " : "a ") + name;
}

// --type of a settings command: a registered type that has the command's feature.
CLI::Validator typeFor(const std::string& command, BoardFeature feature) {
  const std::string names = orList(namesOf(typesWith(feature)));
  return CLI::Validator(
      [command, feature, names](std::string& text) -> std::string {
        const Commissioning* type = commissioningOf(text);
        if (!type) return "'" + text + "' is not " + names;
        if (!type->has(feature))
          return command + " is " + withArticle(names) + " command; " + type->title() +
                 " has no such setting";
        return "";
      },
      "");  // the option's help names them already
}

// The codes a type's baud setting takes, as rates: "4800, 9600, 19200", or "1200-115200" for
// more than three.
std::string baudsOf(const Commissioning& type, bool short_form) {
  const auto [lo, hi] = type.baudCodes();
  if (short_form && hi - lo > 2)
    return std::to_string(baudOfCode(lo)) + "-" + std::to_string(baudOfCode(hi));
  std::vector<int> bauds;
  for (int code = lo; code <= hi; ++code) bauds.push_back(baudOfCode(code));
  return join(bauds);
}

// What --help says of a settings command's value and types, from the registered classes.
std::string rangeHelp(const SettingCommand& s) {
  const std::vector<CommissioningType> types = typesWith(s.feature);
  std::string text;
  auto each = [&types, &text](const std::function<std::string(const CommissioningType&)>& f) {
    text += join(types, ", ", f);
  };
  switch (s.feature) {
    case BoardFeature::kAddress:
      each([](const CommissioningType& t) {
        return std::string(t.type->name) + " 1-" + std::to_string(t.type->max_address);
      });
      text += "; without --address ";
      text += join(types, " / ",
                   [](const CommissioningType& t) { return t.commissioning->addressPath(); });
      return text + ": board alone on the bus";
    case BoardFeature::kBaud:
      text = "a rate or a code: ";
      each([](const CommissioningType& t) {
        const auto [lo, hi] = t.commissioning->baudCodes();
        return std::string(t.type->name) + " " + std::to_string(lo) + "-" + std::to_string(hi) +
               " (" + baudsOf(*t.commissioning, true) + ")";
      });
      return text;
    case BoardFeature::kReturnDelay:
      each([](const CommissioningType& t) {
        const int step = t.commissioning->returnDelayStepMs();
        return std::string(t.type->name) + " 0-" +
               std::to_string(step * t.commissioning->returnDelayMaxUnits()) + " ms in steps of " +
               std::to_string(step);
      });
      return text;
    case BoardFeature::kParity:
      return "none, even or odd";
    case BoardFeature::kPowerDownSave:
      return "on or off";
    case BoardFeature::kFactoryReset:
    case BoardFeature::kLimits:
      break;
  }
  return text;
}

}  // namespace modbus_rtu_driver::commission_args
