// The device settings of modbus_rtu_commission: address, baud, parity, return delay, power-down
// save, factory reset, info. Each change reads the current value first (harmless), asks before
// anything that changes how the device answers, and says when the change takes effect.
#include <cstdio>
#include <functional>
#include <sstream>

#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/devices/ld58a08.h"
#include "modbus_rtu_driver/devices/yespeed_pdu.h"
#include "modbus_rtu_driver/tools/commission_session.h"

namespace modbus_rtu_driver {

namespace {

const char kPowerCycle[] = "It takes effect after the device is powered off and on";

DeviceConfig deviceAt(const std::string& type, int address) {
  DeviceConfig d;
  d.name = d.type = type;
  d.address = address;
  return d;
}

std::string baudText(int code) {
  const int baud = baudOfCode(code);
  return baud ? std::to_string(baud) + " baud (code " + std::to_string(code) + ")"
              : "code " + std::to_string(code) + " (not a baud rate)";
}

std::string parityText(int code) {
  return code == 0   ? "none"
         : code == 1 ? "even"
         : code == 2 ? "odd"
                     : "code " + std::to_string(code);
}

// One setting of a board: how to read and write it and what to say about it.
struct Setting {
  std::string name;  // "baud rate"
  std::string key;   // JSON field
  std::function<std::string(int)> text;
  std::function<Result(uint16_t*)> read;
  std::function<Result(uint16_t)> write;
  std::string after;  // what the user must know once it is written
  bool ask;           // changes how the device answers: confirm first
  int json_scale;     // JSON value = raw x this (return delay in ms)
};

Setting setting(std::string name, std::string key, std::function<std::string(int)> text,
                std::function<Result(uint16_t*)> read, std::function<Result(uint16_t)> write,
                std::string after, bool ask = true, int json_scale = 1) {
  return Setting{std::move(name),
                 std::move(key),
                 std::move(text),
                 std::move(read),
                 std::move(write),
                 std::move(after),
                 ask,
                 json_scale};
}

class DeviceCommands {
 public:
  explicit DeviceCommands(Session& s)
      : s_(s),
        c_(s.cmd),
        lc_(c_.type == kLcRelay8Type.name),
        ld_(deviceAt(kLd58a08Type.name, c_.address < 0 ? 0xFF : c_.address)),
        lc_board_(deviceAt(kLcRelay8Type.name, c_.address)) {}

  int run() {
    const std::string& cmd = c_.command;
    if (cmd == "get-address") return getAddress();
    if (cmd == "set-address") return lc_ ? setLcAddress() : setLdAddress();
    if (cmd == "factory-reset") return factoryReset();
    if (cmd == "info") return info();
    if (cmd == "get-limits") return getLimits();
    if (cmd == "set-limits") return setLimits();
    const Setting which = settingFor(cmd.substr(4));  // get-baud -> baud
    return cmd.compare(0, 4, "get-") == 0 ? show(which) : change(which);
  }

 private:
  std::string device() const { return c_.type + " at address " + std::to_string(c_.address); }
  Json fields() const { return Json().add("type", c_.type).add("address", c_.address); }

  // A setting of the LD58A08 at --address.
  std::function<Result(uint16_t*)> reader(Ld58a08Setting which) {
    return [this, which](uint16_t* v) { return ld_.readSetting(s_.bus, which, v); };
  }
  std::function<Result(uint16_t)> writer(Ld58a08Setting which) {
    return [this, which](uint16_t v) { return ld_.writeSetting(s_.bus, which, v); };
  }

  Setting settingFor(const std::string& what) {
    if (what == "baud") {
      const std::string after =
          std::string(kPowerCycle) + (lc_ ? " (the manual advises about 30 s without power)" : "") +
          "; then reach it with --baud " + std::to_string(baudOfCode(c_.new_value)) + ".";
      if (!lc_)
        return setting("baud rate", "baud_code", baudText, reader(Ld58a08Setting::kBaud),
                       writer(Ld58a08Setting::kBaud), after);
      return setting(
          "baud rate", "baud_code", baudText,
          [this](uint16_t* v) { return lc_board_.readBaudCode(s_.bus, v); },
          [this](uint16_t v) { return lc_board_.writeBaudCode(s_.bus, v); }, after);
    }
    if (what == "parity")
      return setting("parity", "parity_code", parityText, reader(Ld58a08Setting::kParity),
                     writer(Ld58a08Setting::kParity),
                     std::string(kPowerCycle) + "; then reach it with --parity " +
                         parityText(c_.new_value) + ".");
    if (what == "return-delay") {
      std::ostringstream after;
      if (c_.new_value > 0)
        after << "The board waits that long before every answer from now on: give the driver "
                 "reply_delay: "
              << c_.new_value * 0.04 << " for it, and scans a --timeout above it.";
      else
        after << "The board answers without delay from now on.";
      return setting(
          "return delay", "return_delay_ms",
          [](int units) { return std::to_string(units * 40) + " ms"; },
          reader(Ld58a08Setting::kReturnDelay), writer(Ld58a08Setting::kReturnDelay), after.str(),
          true, 40);
    }
    // The power-down save does not change how the board answers: no question.
    return setting(
        "power-down save", "save", [](int v) { return std::string(v ? "on" : "off"); },
        reader(Ld58a08Setting::kPowerDownSave), writer(Ld58a08Setting::kPowerDownSave),
        c_.new_value ? "PWM settings now survive a power cycle." : "", false);
  }

  int show(const Setting& s) {
    uint16_t v = 0;
    const Result r = s.read(&v);
    if (!r.ok()) return s_.out.fail(r, "reading the " + s.name + " of the " + device());
    Json json = fields().add(s.key, v * s.json_scale);
    if (s.key == "baud_code") json.add("baud", baudOfCode(v));
    s_.out.result(device() + ", " + s.name + ": " + s.text(v), json);
    return kExitOk;
  }

  int change(const Setting& s) {
    uint16_t now = 0;
    Result r = s.read(&now);
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
    r = s.write(static_cast<uint16_t>(c_.new_value));
    if (!r.ok()) return s_.out.fail(r, "writing the " + s.name + " of the " + device());
    s_.out.result(
        device() + ": " + s.name + " set to " + to + " (was " + s.text(now) + "). " + s.after,
        json.add("changed", true).add("note", s.after));
    return kExitOk;
  }

  int getAddress() {
    if (lc_ && c_.address >= 0) {  // the board has no address register: it answers or not
      uint16_t code = 0;
      const Result r = lc_board_.readBaudCode(s_.bus, &code);
      if (!r.ok())
        return s_.out.fail(r, "asking the lc_relay8 at address " + std::to_string(c_.address));
      s_.out.result("lc_relay8 answers at address " + std::to_string(c_.address), fields());
      return kExitOk;
    }
    uint16_t address = 0;
    Result r = lc_ ? LcRelay8::readAddressAtZero(s_.bus)
                   : ld_.readSetting(s_.bus, Ld58a08Setting::kAddress, &address);
    const std::string how = c_.address >= 0 ? "" : lc_ ? " through address 0" : " through 0xFF";
    if (!r.ok()) {
      Result told = r;
      if (!lc_ && r.error == ErrorKind::kException && r.exception_code == kIllegalDataAddress)
        told.message +=
            c_.address < 0
                ? "; another board type may have answered (e.g. an LC relay board at its "
                  "factory address 255: try --type lc_relay8)"
                : "; another board type may be at " + std::to_string(c_.address) +
                      " (info --address " + std::to_string(c_.address) + " names it)";
      return s_.out.fail(told, "reading the " + c_.type + " address" + how +
                                   (how.empty() ? "" : " (only one board may be on the bus)"));
    }
    if (!how.empty())
      s_.out.note("read" + how + ": right only with one " + c_.type + " on the bus");
    if (lc_) address = r.values[0];
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

  int setLdAddress() {
    const bool blind = c_.address < 0;  // through 0xFF
    uint16_t current = 0;
    const Result now = ld_.readSetting(s_.bus, Ld58a08Setting::kAddress, &current);
    if (!now.ok())
      return s_.out.fail(now,
                         std::string("reading the ld58a08 address") +
                             (blind ? " through 0xFF (only one board may be on the bus)" : ""));
    const int from = current;
    if (from == c_.new_value) {
      s_.out.result("ld58a08 address is already " + std::to_string(from) + "; nothing written",
                    Json().add("type", c_.type).add("address", from).add("changed", false));
      return kExitOk;
    }
    if (!s_.confirm("Change the ld58a08 address from " + std::to_string(from) + " to " +
                    std::to_string(c_.new_value) +
                    (blind ? " through 0xFF? Every LD58A08 on the bus takes it: only one may be "
                             "connected."
                           : "?") +
                    " It answers only at the new address from then on."))
      return s_.out.fail(kExitNotConfirmed, "not confirmed; nothing was changed");
    const Result r =
        ld_.writeSetting(s_.bus, Ld58a08Setting::kAddress, static_cast<uint16_t>(c_.new_value));
    if (!r.ok()) return s_.out.fail(r, "writing the ld58a08 address");
    Ld58a08 moved(deviceAt(kLd58a08Type.name, c_.new_value));
    uint16_t there = 0;
    const bool answers = moved.readSetting(s_.bus, Ld58a08Setting::kAddress, &there).ok();
    return addressChanged(from, answers && there == c_.new_value);
  }

  int setLcAddress() {
    const Result now = LcRelay8::readAddressAtZero(s_.bus);
    if (!now.ok())
      return s_.out.fail(now,
                         "reading the lc_relay8 address through address 0 (the board must "
                         "be alone on the bus)");
    const int from = now.values[0];
    if (c_.address >= 0 && from != c_.address)
      return s_.out.fail(kExitNotFound, "the board on the bus reports address " +
                                            std::to_string(from) + ", not " +
                                            std::to_string(c_.address) + "; nothing was changed");
    if (from == c_.new_value) {
      s_.out.result("lc_relay8 address is already " + std::to_string(from) + "; nothing written",
                    Json().add("type", c_.type).add("address", from).add("changed", false));
      return kExitOk;
    }
    if (!s_.confirm("Change the lc_relay8 address from " + std::to_string(from) + " to " +
                    std::to_string(c_.new_value) +
                    " through address 0? Every LC board on the bus takes it, and other devices "
                    "see a write to their register 0: only this board may be connected."))
      return s_.out.fail(kExitNotConfirmed, "not confirmed; nothing was changed");
    const Result r = LcRelay8::setAddressAtZero(s_.bus, static_cast<uint8_t>(c_.new_value));
    if (!r.ok()) return s_.out.fail(r, "writing the lc_relay8 address through address 0");
    uint16_t code = 0;
    LcRelay8 moved(deviceAt(kLcRelay8Type.name, c_.new_value));
    return addressChanged(from, moved.readBaudCode(s_.bus, &code).ok());
  }

  int factoryReset() {
    const bool blind = c_.address < 0;
    const std::string where = blind ? "through 0xFF" : "at address " + std::to_string(c_.address);
    if (!s_.confirm("Reset the ld58a08 " + where + (blind ? " (every LD58A08 on the bus)" : "") +
                    " to factory settings: address 1, 9600 baud, no parity, no return delay, PWM "
                    "settings cleared?"))
      return s_.out.fail(kExitNotConfirmed, "not confirmed; nothing was changed");
    // FF 06 00 FB 00 00 ED E5 through 0xFF, as the manual prints it.
    const Result r = ld_.factoryReset(s_.bus);
    if (!r.ok()) return s_.out.fail(r, "factory reset " + where);
    const std::string after =
        "factory settings restored (address 1, 9600 8N1); baud and parity take effect after the "
        "device is powered off and on.";
    s_.out.result("ld58a08 " + where + ": " + after,
                  Json().add("type", c_.type).add("note", after));
    return kExitOk;
  }

  static std::string limitsHuman(const PduLimitRegisters& l) {
    const PduLimitValues v = YespeedPdu::limitValues(l);
    char buf[128];
    std::snprintf(buf, sizeof buf, "over-voltage %.1f V, under-voltage %.1f V, over-current %.2f A",
                  v.over_voltage, v.under_voltage, v.over_current);
    return buf;
  }
  static Json limitsJson(const PduLimitRegisters& l) {
    const PduLimitValues v = YespeedPdu::limitValues(l);
    return Json()
        .add("over_voltage", v.over_voltage)
        .add("under_voltage", v.under_voltage)
        .add("over_current", v.over_current)
        .add("registers", std::vector<uint16_t>(l.begin(), l.end()));
  }

  int getLimits() {
    YespeedPdu pdu(deviceAt(kYespeedPduType.name, c_.address));
    const Result r = pdu.readLimits(s_.bus);
    if (!r.ok()) return s_.out.fail(r, "reading the limits of the " + device());
    s_.out.result(device() + ", limits: " + limitsHuman(pdu.limitRegisters()),
                  fields().merge(limitsJson(pdu.limitRegisters())));
    return kExitOk;
  }

  // Reads the limits first; the ones not given stay. The rules are checked on the merged
  // register values before anything is written, then the PDU's read back must show them.
  int setLimits() {
    YespeedPdu pdu(deviceAt(kYespeedPduType.name, c_.address));
    Result r = pdu.readLimits(s_.bus);
    if (!r.ok()) return s_.out.fail(r, "reading the limits of the " + device());
    const PduLimitRegisters before = pdu.limitRegisters();
    PduLimitChange change;
    for (size_t i = 0; i < 3; ++i)
      if (c_.limits[i] >= 0) change[i] = static_cast<uint16_t>(c_.limits[i]);
    const PduLimitRegisters to = YespeedPdu::mergeLimits(before, change);
    const std::string problem = YespeedPdu::checkLimitRegisters(to);
    if (!problem.empty())
      return s_.out.fail(kExitBadArguments, problem + " (with the limits the PDU holds: " +
                                                limitsHuman(to) + "); nothing was written");
    Json json = fields().merge(limitsJson(to));
    json.add("previous", std::vector<uint16_t>(before.begin(), before.end()));
    if (to == before) {
      s_.out.result(device() + ": limits are already " + limitsHuman(to) + "; nothing written",
                    json.add("changed", false));
      return kExitOk;
    }
    if (!s_.confirm("Change the limits of the " + device() + " from " + limitsHuman(before) +
                    " to " + limitsHuman(to) + "?"))
      return s_.out.fail(kExitNotConfirmed, "not confirmed; nothing was changed");
    r = pdu.writeLimitRegisters(s_.bus, to);
    if (!r.ok()) return s_.out.fail(r, "writing the limits of the " + device());
    s_.out.result(device() + ": limits set to " + limitsHuman(to) + " (was " + limitsHuman(before) +
                      "); read back",
                  json.add("changed", true));
    return kExitOk;
  }

  int info() {
    const Identity id = identifyDevice(s_.bus, static_cast<uint8_t>(c_.address));
    if (!id.present)
      return s_.out.fail(kExitNotFound, "no device answers at address " +
                                            std::to_string(c_.address) +
                                            (id.note.empty() ? "" : " (" + id.note + ")"));
    std::ostringstream human;
    Json json = Json().add("address", c_.address).add("type", id.type);
    human << "address " << c_.address << ": " << id.type;
    Result r;
    if (id.type == kLd58a08Type.name) {
      Ld58a08Settings st;
      r = ld_.readSettings(s_.bus, &st);
      human << "\n  stored baud rate: " << baudText(st.baud_code)
            << "\n  stored parity: " << parityText(st.parity)
            << "\n  return delay: " << st.return_delay * 40
            << " ms\n  power-down save: " << (st.power_down_save ? "on" : "off");
      json.add("baud_code", st.baud_code).add("baud", baudOfCode(st.baud_code));
      json.add("parity_code", st.parity).add("return_delay_ms", st.return_delay * 40);
      json.add("save", st.power_down_save);
    } else if (id.type == kLcRelay8Type.name) {
      uint16_t code = 0;
      r = lc_board_.readBaudCode(s_.bus, &code);
      human << "\n  baud rate: " << baudText(code);
      json.add("baud_code", code).add("baud", baudOfCode(code));
    } else if (id.type == kYespeedPduType.name) {
      YespeedPdu pdu(deviceAt(kYespeedPduType.name, c_.address));
      r = pdu.readTelemetry(s_.bus);
      if (r.ok()) r = pdu.readLimits(s_.bus);
      const PduReading& m = pdu.reading();
      const PduLimitValues& l = pdu.limits();
      human << "\n  " << m.voltage << " V, " << m.current << " A, " << m.power << " W, "
            << m.temperature << " C, " << m.humidity << " %RH\n  limits: over-voltage "
            << l.over_voltage << " V, under-voltage " << l.under_voltage << " V, over-current "
            << l.over_current << " A";
      json.add("voltage", m.voltage).add("current", m.current).add("power", m.power);
      json.add("temperature", m.temperature).add("humidity", m.humidity);
    }
    if (!r.ok()) return s_.out.fail(r, "reading the settings of the " + id.type);
    s_.out.result(human.str(), json);
    return kExitOk;
  }

  Session& s_;
  const CommissionCommand& c_;
  bool lc_;
  Ld58a08 ld_;         // at --address, or 0xFF without it
  LcRelay8 lc_board_;  // at --address
};

}  // namespace

int runDeviceCommand(Session& session) {
  return DeviceCommands(session).run();
}

}  // namespace modbus_rtu_driver
