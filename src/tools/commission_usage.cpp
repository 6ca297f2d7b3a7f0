// modbus_rtu_commission --help: what CLI11's option lists do not say (each command's words,
// the boards' ranges, factory settings and manuals, the scan's duration, confirmations, exit
// codes), after those lists. What is said of a type comes from its descriptor and its class
// (devices/commissioning.h), so a new type shows up here by itself.
#include <algorithm>
#include <functional>
#include <sstream>

#include "modbus_rtu_driver/core/config/link_config.h"
#include "modbus_rtu_driver/core/link/link_types.h"
#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/devices/commissioning.h"
#include "modbus_rtu_driver/tools/commission.h"

namespace modbus_rtu_driver {

namespace {

std::vector<CommissioningType> typesWith(BoardFeature feature) {
  std::vector<CommissioningType> out;
  for (const CommissioningType& t : commissioningTypes())
    if (t.commissioning->has(feature)) out.push_back(t);
  return out;
}

std::string namesWith(BoardFeature feature, const char* separator = "|") {
  return join(typesWith(feature), separator,
              [](const CommissioningType& t) { return std::string(t.type->name); });
}

// The settings commands, one paragraph per command group, for the types registered.
std::string settingsHelp() {
  std::ostringstream h;
  const auto addresses = typesWith(BoardFeature::kAddress);
  if (!addresses.empty()) {
    const std::string names = namesWith(BoardFeature::kAddress);
    h << "  get-address --type " << names << " [--address A]\n"
      << "  set-address --type " << names << " [--address A] NEW\n";
    for (const auto& t : addresses) {
      h << "      " << t.type->name << ": 1-" << t.type->max_address << ", ";
      if (t.commissioning->addressReadableAt())
        h << "at A, or " << t.commissioning->addressPath() << " without --address.\n";
      else
        h << "always " << t.commissioning->addressPath()
          << " (--address A: check it is A first).\n";
    }
    h << "      Without --address the board must be ALONE on the bus: every board of its type "
         "takes\n      the command.\n";
  }
  // A type that also answers another type's factory address garbles that one's replies.
  for (const CommissioningType& t : commissioningTypes()) {
    if (!t.type->also_answers) continue;
    for (const CommissioningType& other : commissioningTypes())
      if (other.type != t.type && other.type->factory.address == t.type->also_answers)
        h << "      " << t.type->name << " boards also answer some requests at "
          << t.type->also_answers << ":\n      move " << other.type->name
          << " boards off their factory address " << other.type->factory.address
          << " before they share a bus with one.\n";
  }
  const auto bauds = typesWith(BoardFeature::kBaud);
  if (!bauds.empty()) {
    h << "  get-baud --type T --address A\n  set-baud --type T --address A BAUD       a rate or "
         "a code:";
    for (const auto& t : bauds) {
      const auto [lo, hi] = t.commissioning->baudCodes();
      std::vector<int> rates;
      for (int code = lo; code <= hi; ++code) rates.push_back(baudOfCode(code));
      h << "\n      " << t.type->name << " " << lo << "-" << hi << " (" << join(rates) << ")";
    }
    h << "\n";
  }
  struct Simple {
    BoardFeature feature;
    const char* get;
    const char* set;
    const char* value;
  };
  for (const Simple& s :
       {Simple{BoardFeature::kParity, "get-parity", "set-parity", "none|even|odd"},
        Simple{BoardFeature::kReturnDelay, "get-return-delay", "set-return-delay", "MS"},
        Simple{BoardFeature::kPowerDownSave, "get-save", "set-save", "on|off"}}) {
    const auto types = typesWith(s.feature);
    if (types.empty()) continue;
    h << "  " << s.get << " --address A / " << s.set << " --address A " << s.value << "\n      "
      << (types.size() > 1 ? "--type " + namesWith(s.feature) + "; " : "");
    if (s.feature == BoardFeature::kReturnDelay)
      h << join(types, ", ", [](const CommissioningType& t) {
        const int step = t.commissioning->returnDelayStepMs();
        return std::string(t.type->name) + " 0-" +
               std::to_string(step * t.commissioning->returnDelayMaxUnits()) + " ms in steps of " +
               std::to_string(step) + " ms";
      });
    else
      h << namesWith(s.feature, ", ");
    if (s.feature == BoardFeature::kPowerDownSave) h << ": power-down save of the PWM settings";
    h << "\n";
  }
  const auto resets = typesWith(BoardFeature::kFactoryReset);
  if (!resets.empty()) {
    h << "  factory-reset --type " << namesWith(BoardFeature::kFactoryReset) << " [--address A]";
    for (const auto& t : resets)
      if (!t.commissioning->addressPath().empty())
        h << "\n      " << t.type->name << " without --address: " << t.commissioning->addressPath()
          << " (every board of the type takes it)";
    h << "\n";
  }
  return h.str();
}

// get-limits / set-limits for the types that have limits.
std::string limitsHelp() {
  std::ostringstream h;
  for (const CommissioningType& t : typesWith(BoardFeature::kLimits)) {
    std::string options;
    std::vector<std::string> names;
    for (const LimitSpec& l : t.commissioning->limitList()) {
      std::string option = std::string("--") + l.name;
      std::replace(option.begin(), option.end(), '_', '-');
      options += " [" + option + " " + l.unit + "]";
      names.push_back(option.substr(2));
    }
    h << "  get-limits --address A                   (" << t.type->name << ": " << join(names)
      << ")\n  set-limits --address A" << options << "\n      (" << t.type->name
      << ") Limits not given stay as the device holds them (it is read first); read\n"
      << "      back after the write. The manual's rules, checked on the register values:\n"
      << "      " << t.commissioning->limitRules() << ".\n";
  }
  return h.str();
}

// Each registered type's addresses, factory settings and manual (its descriptor).
std::string typesHelp() {
  std::ostringstream h;
  h << "\nDevice types (factory settings; the manual the register map comes from):\n";
  for (const CommissioningType& t : commissioningTypes()) {
    const FactorySettings& f = t.type->factory;
    h << "  " << t.type->name << ": addresses 1-" << t.type->max_address;
    if (f.address) h << ", factory address " << f.address;
    if (f.baud) h << ", " << lineName(f.baud, f.parity);
    if (t.commissioning->has(BoardFeature::kReturnDelay))
      h << ", return delay up to "
        << t.commissioning->returnDelayStepMs() * t.commissioning->returnDelayMaxUnits() << " ms";
    h << " (" << t.type->manual << ")\n";
  }
  return h.str();
}

}  // namespace

std::string commissionHelpDetails() {
  return R"(
Details (COMMAND --help lists a command's options):
  scan [--from A] [--to B | --addresses 1-5,255] [--bauds 9600,19200|all]
       [--parities none,even,odd|all] [--first]
      Harmless reads at every address (default 1-255) and line setting (default --baud and
      --parity); names the type of each device that answers. Ctrl-C stops early and still
      lists what was found. A silent address costs one read: the scan timeout (0.05 s + 30
      characters at --baud: 0.081 s at the default 9600 8N1) plus the 3.5-character gap kept
      before the next request. Every baud and parity over 1-255 (--bauds all --parities all)
      is 255 x 8 x 3 = 6120 reads: 6120 x 0.081 s = 8.3 min of timeouts + 0.8 min of gaps,
      about 9 minutes (each device found adds up to 4 reads).
      Through a Modbus TCP gateway (--port tcp://, the bus node's share) the gateway answers
      every request itself, exception 0B once nothing answered on its line: that is no device.
      The scan waits up to 3 s for each answer, since a request given up sooner stays queued in
      the gateway and the next addresses wait behind it; a silent address then costs the
      gateway's own response timeout x (retries + 1). A --timeout must stay above that.
  info --address A                         type and settings of the device at A
)" + settingsHelp() +
         R"()" + limitsHelp() +
         R"(  read --address A TABLE START [COUNT]    TABLE: coil, discrete_input, holding_register,
                                           input_register
  write --address A coil|holding_register START VALUE... [--multiple]
                                           FC05/FC06 for one value, FC15/FC16 for more
                                           (--multiple: FC15/FC16 always)
  watch --address A TABLE START [COUNT] [--interval S] [--count N]
      Polls and prints a line only when something changed; Ctrl-C ends it.

Numbers may be decimal or 0x-hex. Changes to how a device answers (address, baud, parity,
return delay, factory reset) and protection limits ask for confirmation on stdin unless --yes;
without a "y" (or at end of input) nothing is changed.
Baud and parity take effect after the device is powered off and on.
--port: one of
)" + linkTypesHelp() +
         R"(--timeout: wait for a reply, default 0.05 s + 30 characters for scans (3 s through tcp://),
and for other commands more by the longest return delay below (a board with a return delay
waits that long before answering; scan such a board with a --timeout above its return delay).

exit codes: 0 ok, 2 bad arguments, 3 not found / no answer (also a gateway's exception 0B),
4 refused by the device (Modbus exception), 5 other bus error (CRC, I/O, port, a gateway's
exception 0A), 6 not confirmed by the user
)" + typesHelp();
}

}  // namespace modbus_rtu_driver
