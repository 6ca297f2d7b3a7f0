#include "modbus_rtu_driver/tools/commission_validators.h"

#include "modbus_rtu_driver/core/config/link_config.h"
#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/core/modbus/types.h"
#include "modbus_rtu_driver/tools/commission_values.h"

namespace modbus_rtu_driver::commission_args {

// CLI11's checks of one option's value on its own; CLI11 puts the option's name in front. The
// check is CLI11's (CLI::Range, CLI::IsMember); the refusal is in this tool's words.
CLI::Validator refusing(const CLI::Validator& check, const Message& message) {
  const std::string description = check.get_description();
  return CLI::Validator(
      [check, message](std::string& text) {
        std::string copy = text;
        return check(copy).empty() ? std::string() : message(text);
      },
      description);
}

// An integer in lo-hi, decimal or 0x-hex, rewritten as decimal for CLI11 to convert (so "010"
// is ten with every CLI11 version, not octal).
CLI::Validator intRange(long lo, long hi) {
  const CLI::Range range(lo, hi);
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        long v = 0;
        std::string decimal;
        if (toLong(text, &v)) decimal = std::to_string(v);
        if (decimal.empty() || !range(decimal).empty())
          return "'" + text + "' is outside " + std::to_string(lo) + "-" + std::to_string(hi);
        text = decimal;
        return "";
      },
      std::to_string(lo) + "-" + std::to_string(hi));
}

// An integer whose range depends on another value (COUNT: on the table), checked after parsing.
CLI::Validator anInteger(const std::string& range) {
  return CLI::Validator(
      [range](std::string& text) -> std::string {
        long v = 0;
        if (!toLong(text, &v)) return "'" + text + "' is not a number (" + range + ")";
        text = std::to_string(v);
        return "";
      },
      "N");
}

CLI::Validator secondsRange(double lo, double hi) {
  const CLI::Range range(lo, hi);
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        double v = 0;
        std::string copy = text;
        if (toDouble(text, &v) && range(copy).empty()) return "";
        return "'" + text + "' is outside " + rangeText(lo, hi) + " s";
      },
      rangeText(lo, hi) + " s");
}

// A standard rate (core/config/link_config.h), checked as an integer first.
CLI::Validator baudRate() {
  const CLI::Validator number = intRange(1200, 115200);
  const CLI::Validator standard = refusing(
      CLI::IsMember(std::vector<int>(std::begin(kStandardBauds), std::end(kStandardBauds))),
      [](const std::string& text) { return "'" + text + "' is not one of " + standardBaudList(); });
  return CLI::Validator(
      [number, standard](std::string& text) {
        std::string problem = number(text);
        return problem.empty() ? standard(text) : problem;
      },
      "1200-115200");
}

// A parity by its name (parseParity's check: a letter is refused with the name to write).
CLI::Validator parityWords(const std::string& suffix) {
  return CLI::Validator(
      [suffix](std::string& text) -> std::string {
        std::string problem;
        return parseParity(text, &problem) ? "" : problem + suffix;
      },
      "none|even|odd");
}

// The name, checked, as its Parity's number for CLI11 to convert.
CLI::Validator parityOption() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::string problem;
        const auto parity = parseParity(text, &problem);
        if (parity) text = std::to_string(static_cast<int>(*parity));
        return problem;
      },
      "none|even|odd");
}

CLI::Validator baudList() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const CLI::Validator rate = baudRate();
        for (std::string b : splitList(text == "all" ? standardBaudList() : text))
          if (!rate(b).empty())
            return "'" + b + "' is not one of " + standardBaudList() + " (or all)";
        return "";
      },
      "LIST|all");
}

CLI::Validator parityList() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (text == "all") return "";
        const CLI::Validator name = parityWords(" (or all)");
        for (std::string p : splitList(text)) {
          std::string problem = name(p);
          if (!problem.empty()) return problem;
        }
        return "";
      },
      "LIST|all");
}

// A table by its one name; a spelling of earlier versions is refused with the name to use.
CLI::Validator tableName() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::string problem;
        return parseTableName(text, &problem) ? "" : problem;
      },
      join(kTableNames, "|", [](const Named<Table>& row) { return std::string(row.name); }));
}

}  // namespace modbus_rtu_driver::commission_args
