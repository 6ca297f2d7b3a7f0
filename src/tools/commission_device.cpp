// The device settings of modbus_rtu_commission: address, baud, parity, return delay, power-down
// save, factory reset, info. Each change reads the current value first (harmless), asks before
// anything that changes how the device answers, and says when the change takes effect.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>
#include <variant>

#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/devices/commissioning.h"
#include "modbus_rtu_driver/tools/commission_session.h"

namespace modbus_rtu_driver {

namespace {

const char kPowerCycle[] = "It takes effect after the device is powered off and on";

// "address 1, 9600 baud, no parity" from the type's descriptor.
std::string factoryText(const FactorySettings& f) {
  return "address " + std::to_string(f.address) + ", " + std::to_string(f.baud) + " baud, " +
         (f.parity == Parity::kNone ? std::string("no") : parityName(f.parity)) + " parity";
}

// One setting of a board: what to say about it; the type's class reads and writes it.
struct Setting {
  BoardFeature feature;
  std::string name;  // "baud rate"
  std::string key;   // JSON field
  std::function<std::string(int)> text;
  std::string after;  // what the user must know once it is written
  bool ask;           // changes how the device answers: confirm first
  int json_scale;     // JSON value = raw x this (return delay in ms)
};

class DeviceCommands {
 public:
  explicit DeviceCommands(Session& s) : s_(s), c_(s.cmd), type_(commissioningOf(c_.type)) {}

  int run() {
    const std::string& cmd = c_.command;
    if (cmd == "info") return info();
    if (!type_) return s_.out.fail(kExitBadArguments, "--type: '" + c_.type + "' is not known");
    if (cmd == "get-limits") return getLimits();
    if (cmd == "set-limits") return setLimits();
    if (cmd == "get-address") return getAddress();
    if (cmd == "set-address") return setAddress();
    if (cmd == "factory-reset") return factoryReset();
    const Setting which = settingFor(cmd.substr(4));  // get-baud -> baud
    return cmd.compare(0, 4, "get-") == 0 ? show(which) : change(which);
  }

 private:
  std::string device() const { return c_.type + " at address " + std::to_string(c_.address); }
  Json fields() const { return Json().add("type", c_.type).add("address", c_.address); }

  Setting settingFor(const std::string& what) {
    if (what == "baud") {
      const std::string after = std::string(kPowerCycle) + type_->powerCycleAdvice() +
                                "; then reach it with --baud " +
                                std::to_string(baudOfCode(c_.new_value)) + ".";
      return {BoardFeature::kBaud, "baud rate", "baud_code", baudCodeText, after, true, 1};
    }
    if (what == "parity")
      return {BoardFeature::kParity,
              "parity",
              "parity_code",
              parityCodeText,
              std::string(kPowerCycle) + "; then reach it with --parity " +
                  parityCodeText(c_.new_value) + ".",
              true,
              1};
    if (what == "return-delay") {
      const int step_ms = type_->returnDelayStepMs();
      std::ostringstream after;
      if (c_.new_value > 0)
        after << "The board waits that long before every answer from now on: give the driver "
                 "reply_delay: "
              << c_.new_value * step_ms / 1000.0 << " for it, and scans a --timeout above it.";
      else
        after << "The board answers without delay from now on.";
      return {BoardFeature::kReturnDelay,
              "return delay",
              "return_delay_ms",
              [step_ms](int units) { return std::to_string(units * step_ms) + " ms"; },
              after.str(),
              true,
              step_ms};
    }
    // The power-down save does not change how the board answers: no question.
    return {BoardFeature::kPowerDownSave,
            "power-down save",
            "save",
            [](int v) { return std::string(v ? "on" : "off"); },
            c_.new_value ? "PWM settings now survive a power cycle." : "",
            false,
            1};
  }

  Result read(const Setting& s, uint16_t* v) {
    return type_->readSetting(s_.transport, c_.address, s.feature, v);
  }

  int show(const Setting& s) {
    uint16_t v = 0;
    const Result r = read(s, &v);
    if (!r.ok()) return s_.out.fail(r, "reading the " + s.name + " of the " + device());
    Json json = fields().add(s.key, v * s.json_scale);
    if (s.feature == BoardFeature::kBaud) json.add("baud", baudOfCode(v));
    s_.out.result(device() + ", " + s.name + ": " + s.text(v), json);
    return kExitOk;
  }

  int change(const Setting& s) {
    uint16_t now = 0;
    Result r = read(s, &now);
    if (!r.ok()) return s_.out.fail(r, "reading the " + s.name + " of the " + device());
    const std::string to = s.text(c_.new_value);
    Json json =
        fields().add(s.key, c_.new_value * s.json_scale).add("previous", now * s.json_scale);
    if (now == c_.new_value) {
      s_.out.result(device() + ": " + s.name + " is already " + to + "; nothing written",
                    json.add("changed", false));
      return kExitOk;
    }
    if (s.ask && !s_.confirm("Change the " + s.name + " of the " + device() + " from " +
                             s.text(now) + " to " + to + "? " + s.after))
      return s_.out.fail(kExitNotConfirmed, "not confirmed; nothing was changed");
    r = type_->writeSetting(s_.transport, c_.address, s.feature,
                            static_cast<uint16_t>(c_.new_value));
    if (!r.ok()) return s_.out.fail(r, "writing the " + s.name + " of the " + device());
    s_.out.result(
        device() + ": " + s.name + " set to " + to + " (was " + s.text(now) + "). " + s.after,
        json.add("changed", true).add("note", s.after));
    return kExitOk;
  }

  int getAddress() {
    // A board with no address register at its own address answers there or not.
    if (!type_->addressReadableAt() && c_.address >= 0) {
      const Result r = type_->answersAt(s_.transport, c_.address);
      if (!r.ok())
        return s_.out.fail(r,
                           "asking the " + c_.type + " at address " + std::to_string(c_.address));
      s_.out.result(c_.type + " answers at address " + std::to_string(c_.address), fields());
      return kExitOk;
    }
    uint16_t address = 0;
    const int at = type_->addressReadableAt() && c_.address >= 0 ? c_.address : kBlind;
    const Result r = type_->readAddress(s_.transport, at, &address);
    const std::string how = at == kBlind ? " " + type_->addressPath() : "";
    if (!r.ok()) {
      Result told = r;
      told.message += type_->addressReadHint(r, at);
      return s_.out.fail(told, "reading the " + c_.type + " address" + how +
                                   (how.empty() ? "" : " (only one board may be on the bus)"));
    }
    if (!how.empty())
      s_.out.note("read" + how + ": right only with one " + c_.type + " on the bus");
    s_.out.result(c_.type + " address: " + std::to_string(address),
                  Json().add("type", c_.type).add("address", static_cast<int>(address)));
    return kExitOk;
  }

  // The board answers at its new address from the next request on (its reply to the change
  // still comes from the old one); check it does.
  int addressChanged(int from, bool answers) {
    const int to = c_.new_value;
    if (!answers)
      s_.out.note("warning: the board accepted address " + std::to_string(to) +
                  " but does not answer there yet; power it off and on, then scan");
    s_.out.result(c_.type + " address changed from " + std::to_string(from) + " to " +
                      std::to_string(to) + (answers ? "; it answers at " + std::to_string(to) : ""),
                  Json()
                      .add("type", c_.type)
                      .add("previous", from)
                      .add("address", to)
                      .add("answers", answers));
    return kExitOk;
  }

  // Reads the current address first: at --address where the board has an address register
  // there, else through its path (checked against --address when one was given).
  int setAddress() {
    const int at = type_->addressReadableAt() && c_.address >= 0 ? c_.address : kBlind;
    const bool blind = at == kBlind;
    const std::string path = blind ? " " + type_->addressPath() : "";
    uint16_t current = 0;
    const Result now = type_->readAddress(s_.transport, at, &current);
    if (!now.ok())
      return s_.out.fail(now, "reading the " + c_.type + " address" + path +
                                  (blind ? " (only one board may be on the bus)" : ""));
    const int from = current;
    if (blind && c_.address >= 0 && from != c_.address)
      return s_.out.fail(kExitNotFound, "the board on the bus reports address " +
                                            std::to_string(from) + ", not " +
                                            std::to_string(c_.address) + "; nothing was changed");
    if (from == c_.new_value) {
      s_.out.result(c_.type + " address is already " + std::to_string(from) + "; nothing written",
                    Json().add("type", c_.type).add("address", from).add("changed", false));
      return kExitOk;
    }
    const std::string after = type_->afterAddressChange();
    if (!s_.confirm("Change the " + c_.type + " address from " + std::to_string(from) + " to " +
                    std::to_string(c_.new_value) +
                    (blind ? path + "? " + type_->addressPathWarning() : "?") +
                    (after.empty() ? "" : " " + after)))
      return s_.out.fail(kExitNotConfirmed, "not confirmed; nothing was changed");
    const Result r = type_->writeAddress(s_.transport, at, static_cast<uint16_t>(c_.new_value));
    if (!r.ok()) return s_.out.fail(r, "writing the " + c_.type + " address" + path);
    return addressChanged(from, type_->answersAt(s_.transport, c_.new_value).ok());
  }

  // The factory settings named are the descriptor's (core/device_types/<type>.h).
  int factoryReset() {
    const DeviceDescriptor& type = *commissioningClasses().find(c_.type)->type;
    const bool blind = c_.address < 0;
    const std::string where =
        blind ? type_->addressPath() : "at address " + std::to_string(c_.address);
    if (!s_.confirm("Reset the " + c_.type + " " + where +
                    (blind ? type_->factoryResetPathWarning() : "") + " to factory settings: " +
                    factoryText(type.factory) + type_->factoryResetAlsoText() + "?"))
      return s_.out.fail(kExitNotConfirmed, "not confirmed; nothing was changed");
    const Result r = type_->factoryReset(s_.transport, blind ? kBlind : c_.address);
    if (!r.ok()) return s_.out.fail(r, "factory reset " + where);
    const std::string after =
        "factory settings restored (address " + std::to_string(type.factory.address) + ", " +
        lineName(type.factory.baud, type.factory.parity) +
        "); baud and parity take effect after the device is powered off and on.";
    s_.out.result(c_.type + " " + where + ": " + after,
                  Json().add("type", c_.type).add("note", after));
    return kExitOk;
  }

  // "over-voltage 250.0 V, under-voltage 200.0 V, over-current 16.00 A"
  std::string limitsHuman(const std::vector<uint16_t>& regs) const {
    const std::vector<LimitSpec> limits = type_->limitList();
    std::vector<std::string> items;
    for (size_t i = 0; i < limits.size() && i < regs.size(); ++i) {
      std::string name = limits[i].name;
      std::replace(name.begin(), name.end(), '_', '-');
      char value[32];
      std::snprintf(value, sizeof value, "%.*f", limits[i].decimals,
                    regs[i] / std::pow(10.0, limits[i].decimals));
      items.push_back(name + " " + value + " " + limits[i].unit);
    }
    return join(items);
  }
  Json limitsJson(const std::vector<uint16_t>& regs) const {
    const std::vector<LimitSpec> limits = type_->limitList();
    Json json;
    for (size_t i = 0; i < limits.size() && i < regs.size(); ++i)
      json.add(limits[i].name, regs[i] / std::pow(10.0, limits[i].decimals));
    return json.add("registers", regs);
  }

  int getLimits() {
    std::vector<uint16_t> regs;
    const Result r = type_->readLimits(s_.transport, c_.address, &regs);
    if (!r.ok()) return s_.out.fail(r, "reading the limits of the " + device());
    s_.out.result(device() + ", limits: " + limitsHuman(regs), fields().merge(limitsJson(regs)));
    return kExitOk;
  }

  // Reads the limits first; the ones not given stay. The rules are checked on the merged
  // register values before anything is written, then the device's read back must show them.
  int setLimits() {
    std::vector<uint16_t> before;
    Result r = type_->readLimits(s_.transport, c_.address, &before);
    if (!r.ok()) return s_.out.fail(r, "reading the limits of the " + device());
    std::vector<uint16_t> to = before;
    for (size_t i = 0; i < to.size() && i < c_.limits.size(); ++i)
      if (c_.limits[i] >= 0) to[i] = static_cast<uint16_t>(c_.limits[i]);
    const std::string problem = type_->checkLimits(to);
    if (!problem.empty())
      return s_.out.fail(kExitBadArguments, problem + " (with the limits the device holds: " +
                                                limitsHuman(to) + "); nothing was written");
    Json json = fields().merge(limitsJson(to));
    json.add("previous", before);
    if (to == before) {
      s_.out.result(device() + ": limits are already " + limitsHuman(to) + "; nothing written",
                    json.add("changed", false));
      return kExitOk;
    }
    if (!s_.confirm("Change the limits of the " + device() + " from " + limitsHuman(before) +
                    " to " + limitsHuman(to) + "?"))
      return s_.out.fail(kExitNotConfirmed, "not confirmed; nothing was changed");
    r = type_->writeLimits(s_.transport, c_.address, to);
    if (!r.ok()) return s_.out.fail(r, "writing the limits of the " + device());
    s_.out.result(device() + ": limits set to " + limitsHuman(to) + " (was " + limitsHuman(before) +
                      "); read back",
                  json.add("changed", true));
    return kExitOk;
  }

  int info() {
    const Identity id = identifyDevice(s_.transport, static_cast<uint8_t>(c_.address));
    if (!id.present)
      return s_.out.fail(kExitNotFound, "no device answers at address " +
                                            std::to_string(c_.address) +
                                            (id.note.empty() ? "" : " (" + id.note + ")"));
    Json json = Json().add("address", c_.address).add("type", id.type);
    std::string human = "address " + std::to_string(c_.address) + ": " + id.type;
    if (const Commissioning* type = commissioningOf(id.type)) {
      InfoReport report;
      const Result r = type->report(s_.transport, static_cast<uint8_t>(c_.address), &report);
      if (!r.ok()) return s_.out.fail(r, "reading the settings of the " + id.type);
      human += report.human;
      for (const auto& [key, value] : report.fields)
        std::visit([&json, &key = key](const auto& v) { json.add(key, v); }, value);
    }
    s_.out.result(human, json);
    return kExitOk;
  }

  Session& s_;
  const CommissionCommand& c_;
  const Commissioning* type_;  // --type's class; null for info
};

}  // namespace

int runDeviceCommand(Session& session) {
  return DeviceCommands(session).run();
}

}  // namespace modbus_rtu_driver
