// Running modbus_rtu_commission's commands on a port through RtuLink.
#include <chrono>
#include <istream>
#include <ostream>
#include <sstream>
#include <thread>

#include "modbus_rtu_driver/core/rtu_link.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/devices/ld58a08.h"
#include "modbus_rtu_driver/tools/commission.h"

namespace modbus_rtu_driver {

namespace {

const int kLdBauds[] = {1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200};

int exitFor(const Result& r) {
  switch (r.error) {
    case ErrorKind::kNone:
      return kExitOk;
    case ErrorKind::kTimeout:
      return kExitNotFound;
    case ErrorKind::kException:
      return kExitRefused;
    case ErrorKind::kInvalidArgument:
      return kExitBadArguments;
    default:
      return kExitBusError;
  }
}

std::string jsonList(const std::vector<uint16_t>& v) {
  std::string s = "[";
  for (size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + std::to_string(v[i]);
  return s + "]";
}

class Session {
 public:
  Session(const CommissionCommand& c, std::istream& in, std::ostream& out, std::ostream& err,
          const std::atomic<bool>& stop)
      : c_(c), in_(in), out_(out), err_(err), stop_(stop) {}

  int run() {
    link_ = std::make_unique<RtuLink>(c_.link);
    if (c_.command != "scan") {
      std::string error;
      if (!link_->connect(&error)) return fail(kExitBusError, error);
    }
    const std::string& cmd = c_.command;
    if (cmd == "scan") return scan();
    if (cmd == "info") return info();
    if (cmd == "get-address") return getAddress();
    if (cmd == "set-address") return setAddress();
    if (cmd == "get-baud") return getBaud();
    if (cmd == "get-parity") return readOne(Ld58a08::kParityRegister, "parity");
    if (cmd == "read") return read();
    if (cmd == "write") return write();
    if (cmd == "watch") return watch();
    return change();  // set-baud, set-parity, set-return-delay, set-save, factory-reset
  }

 private:
  uint8_t at() const { return static_cast<uint8_t>(c_.address); }

  int fail(int code, const std::string& message) {
    if (c_.json)
      out_ << "{\"ok\":false,\"exit\":" << code << ",\"error\":\"" << message << "\"}\n";
    else
      err_ << "error: " << message << "\n";
    return code;
  }
  int fail(const Result& r) { return fail(exitFor(r), r.message); }

  bool confirm(const std::string& what) {
    if (c_.yes) return true;
    err_ << what << " Continue? [y/N] " << std::flush;
    std::string answer;
    if (!std::getline(in_, answer)) return false;
    return answer == "y" || answer == "Y" || answer == "yes";
  }

  void reply(const std::string& human, const std::string& json_fields) {
    if (c_.json)
      out_ << "{\"ok\":true," << json_fields << "}\n";
    else
      out_ << human << "\n";
  }

  // Harmless reads only: presence by one coil, type by a register only that type has.
  std::string identify(uint8_t address) {
    const Result present = link_->execute(Request::readCoils(address, 0, 1));
    if (present.error == ErrorKind::kTimeout || present.error == ErrorKind::kCrc ||
        present.error == ErrorKind::kIo || present.error == ErrorKind::kNotConnected)
      return {};
    const Result lc =
        link_->execute(Request::readHoldingRegisters(address, LcRelay8::kBaudReadRegister, 1));
    if (lc.ok() && lc.values[0] >= 2 && lc.values[0] <= 4) return "lc_relay8";
    if (link_->execute(Request::readInputRegisters(address, 0, 5)).ok()) return "yespeed_pdu";
    const Result ld =
        link_->execute(Request::readHoldingRegisters(address, Ld58a08::kAddressRegister, 1));
    if (ld.ok() && ld.values[0] == address) return "ld58a08";
    return "unknown modbus device";
  }

  int scan() {
    struct Found {
      int address, baud;
      Parity parity;
      std::string type;
    };
    std::vector<Found> found;
    const int total =
        (c_.to - c_.from + 1) * static_cast<int>(c_.bauds.size() * c_.parities.size());
    int done = 0;
    for (int baud : c_.bauds) {
      for (Parity parity : c_.parities) {
        LinkConfig l = c_.link;
        l.baud = baud;
        l.parity = parity;
        link_ = std::make_unique<RtuLink>(l);
        std::string error;
        if (!link_->connect(&error)) return fail(kExitBusError, error);
        for (int a = c_.from; a <= c_.to && !stop_; ++a, ++done) {
          err_ << "\rscanning " << baud << " " << parityName(parity) << ": address " << a << " ("
               << done * 100 / total << " %, " << found.size() << " found)   " << std::flush;
          const std::string type = identify(static_cast<uint8_t>(a));
          if (type.empty()) continue;
          found.push_back({a, baud, parity, type});
          if (!c_.json)
            out_ << "\rfound " << type << " at address " << a << ", " << baud << " baud, "
                 << parityName(parity) << " parity" << std::string(20, ' ') << "\n";
          if (c_.first_only) break;
        }
        if (stop_ || (c_.first_only && !found.empty())) break;
      }
      if (stop_ || (c_.first_only && !found.empty())) break;
    }
    err_ << "\n" << (stop_ ? "scan stopped early; " : "") << found.size() << " device(s) found\n";
    if (c_.json) {
      out_ << "{\"ok\":" << (found.empty() ? "false" : "true")
           << ",\"complete\":" << (stop_ ? "false" : "true") << ",\"devices\":[";
      for (size_t i = 0; i < found.size(); ++i)
        out_ << (i ? "," : "") << "{\"address\":" << found[i].address
             << ",\"baud\":" << found[i].baud << ",\"parity\":\"" << parityName(found[i].parity)
             << "\",\"type\":\"" << found[i].type << "\"}";
      out_ << "]}\n";
    }
    return found.empty() ? kExitNotFound : kExitOk;
  }

  int info() {
    const std::string type = identify(at());
    if (type.empty())
      return fail(kExitNotFound, "no answer at address " + std::to_string(c_.address));
    std::ostringstream human, json;
    human << "address " << c_.address << ": " << type;
    json << "\"address\":" << c_.address << ",\"type\":\"" << type << "\"";
    if (type == "ld58a08") {
      const Result r = link_->execute(Request::readHoldingRegisters(at(), 0x00FA, 6));
      if (!r.ok()) return fail(r);
      const uint16_t code = r.values[4];
      human << "\n  baud code " << code << " (" << (code < 8 ? kLdBauds[code] : 0) << ")"
            << "\n  parity " << r.values[5] << "\n  return delay " << r.values[2] * 40 << " ms"
            << "\n  power-down save " << (r.values[0] ? "on" : "off");
      json << ",\"baud_code\":" << code << ",\"parity\":" << r.values[5]
           << ",\"return_delay_ms\":" << r.values[2] * 40 << ",\"save\":" << r.values[0];
    } else if (type == "lc_relay8") {
      const Result r =
          link_->execute(Request::readHoldingRegisters(at(), LcRelay8::kBaudReadRegister, 1));
      if (!r.ok()) return fail(r);
      human << "\n  baud code " << r.values[0] << " (" << kLdBauds[r.values[0] & 7] << ")";
      json << ",\"baud_code\":" << r.values[0];
    }
    reply(human.str(), json.str());
    return kExitOk;
  }

  int getAddress() {
    Result r;
    if (c_.type == "lc_relay8" && c_.address < 0) {
      r = LcRelay8::readAddressAtZero(*link_);
    } else {
      const uint8_t a = c_.address < 0 ? 0xFF : at();
      r = c_.type == "lc_relay8"
              ? link_->execute(Request::readCoils(a, 0, 1))  // the LC board answers where it is
              : link_->execute(Request::readHoldingRegisters(a, Ld58a08::kAddressRegister, 1));
      if (r.ok() && c_.type == "lc_relay8") r.values = {a};
    }
    if (!r.ok()) return fail(r);
    reply("address " + std::to_string(r.values[0]), "\"address\":" + std::to_string(r.values[0]));
    return kExitOk;
  }

  int setAddress() {
    const bool lc = c_.type == "lc_relay8";
    const std::string how = lc ? "through address 0 (only this board may be on the bus)"
                            : c_.address < 0 ? "through 0xFF (only this board may be on the bus)"
                                             : "at address " + std::to_string(c_.address);
    if (!confirm("Set the " + c_.type + " address to " + std::to_string(c_.new_value) + " " + how +
                 "; it will answer only there."))
      return fail(kExitNotConfirmed, "not confirmed; nothing was sent");
    const Result r = lc ? LcRelay8::setAddressAtZero(*link_, static_cast<uint8_t>(c_.new_value))
                        : link_->execute(Request::writeSingleRegister(
                              c_.address < 0 ? 0xFF : at(), Ld58a08::kAddressRegister,
                              static_cast<uint16_t>(c_.new_value)));
    if (!r.ok()) return fail(r);
    reply(
        "address set to " + std::to_string(c_.new_value) + "; the board answers there from now on",
        "\"address\":" + std::to_string(c_.new_value));
    return kExitOk;
  }

  int getBaud() {
    const uint16_t reg =
        c_.type == "lc_relay8" ? LcRelay8::kBaudReadRegister : Ld58a08::kBaudRegister;
    const Result r = link_->execute(Request::readHoldingRegisters(at(), reg, 1));
    if (!r.ok()) return fail(r);
    const int code = r.values[0];
    const int baud = code < 8 ? kLdBauds[code] : 0;
    reply("baud code " + std::to_string(code) + " = " + std::to_string(baud) + " baud",
          "\"baud_code\":" + std::to_string(code) + ",\"baud\":" + std::to_string(baud));
    return kExitOk;
  }

  int readOne(uint16_t reg, const char* what) {
    const Result r = link_->execute(Request::readHoldingRegisters(at(), reg, 1));
    if (!r.ok()) return fail(r);
    reply(std::string(what) + " " + std::to_string(r.values[0]),
          "\"" + std::string(what) + "\":" + std::to_string(r.values[0]));
    return kExitOk;
  }

  // set-baud, set-parity, set-return-delay, set-save, factory-reset
  int change() {
    const std::string& cmd = c_.command;
    Request req;
    std::string what, note;
    bool ask = true;
    if (cmd == "set-baud") {
      const bool lc = c_.type == "lc_relay8";
      req = lc ? Request::writeMultipleRegisters(at(), LcRelay8::kBaudWriteRegister,
                                                 {static_cast<uint16_t>(c_.new_value)})
               : Request::writeSingleRegister(at(), Ld58a08::kBaudRegister,
                                              static_cast<uint16_t>(c_.new_value));
      what = "Set the baud rate to " + std::to_string(kLdBauds[c_.new_value]) + ".";
      note = "baud rate stored; it takes effect after the device is powered off and on";
    } else if (cmd == "set-parity") {
      req = Request::writeSingleRegister(at(), Ld58a08::kParityRegister,
                                         static_cast<uint16_t>(c_.new_value));
      what = "Set the parity code to " + std::to_string(c_.new_value) + ".";
      note = "parity stored; it takes effect after the device is powered off and on";
    } else if (cmd == "set-return-delay") {
      req = Request::writeSingleRegister(at(), Ld58a08::kReturnDelayRegister,
                                         static_cast<uint16_t>(c_.new_value));
      what =
          "Make the board wait " + std::to_string(c_.new_value * 40) + " ms before every answer.";
      note =
          "return delay set; give the driver reply_delay: " + std::to_string(c_.new_value * 0.04);
    } else if (cmd == "set-save") {
      req = Request::writeSingleRegister(at(), Ld58a08::kPowerDownSaveRegister,
                                         static_cast<uint16_t>(c_.new_value));
      note = std::string("power-down save ") + (c_.new_value ? "on" : "off");
      ask = false;
    } else {  // factory-reset
      req = Request::writeSingleRegister(c_.address < 0 ? 0xFF : at(),
                                         Ld58a08::kFactoryResetRegister, 0);
      what = "Reset the LD58A08 to factory settings (address 1, 9600 baud, no parity).";
      note = "factory settings restored; power the board off and on";
    }
    if (ask && !confirm(what)) return fail(kExitNotConfirmed, "not confirmed; nothing was sent");
    const Result r = link_->execute(req);
    if (!r.ok()) return fail(r);
    reply(note, "\"message\":\"" + note + "\"");
    return kExitOk;
  }

  Request readRequest() const {
    const auto s = static_cast<uint16_t>(c_.start);
    const auto n = static_cast<uint16_t>(c_.count);
    if (c_.table == "coils") return Request::readCoils(at(), s, n);
    if (c_.table == "discrete-inputs") return Request::readDiscreteInputs(at(), s, n);
    if (c_.table == "holding") return Request::readHoldingRegisters(at(), s, n);
    return Request::readInputRegisters(at(), s, n);
  }

  void print(const std::vector<uint16_t>& values) {
    std::ostringstream human;
    for (size_t i = 0; i < values.size(); ++i)
      human << (i ? "\n" : "") << c_.table << " " << c_.start + static_cast<int>(i) << ": "
            << values[i];
    reply(human.str(), "\"address\":" + std::to_string(c_.address) + ",\"table\":\"" + c_.table +
                           "\",\"start\":" + std::to_string(c_.start) +
                           ",\"values\":" + jsonList(values));
  }

  int read() {
    const Result r = link_->execute(readRequest());
    if (!r.ok()) return fail(r);
    print(r.values);
    return kExitOk;
  }

  int write() {
    const auto s = static_cast<uint16_t>(c_.start);
    Request req;
    if (c_.table == "coils")
      req = c_.values.size() == 1
                ? Request::writeSingleCoil(at(), s, c_.values[0] != 0)
                : Request::writeMultipleCoils(
                      at(), s, std::vector<bool>(c_.values.begin(), c_.values.end()));
    else
      req = c_.values.size() == 1 ? Request::writeSingleRegister(at(), s, c_.values[0])
                                  : Request::writeMultipleRegisters(at(), s, c_.values);
    const Result r = link_->execute(req);
    if (!r.ok()) return fail(r);
    reply(std::to_string(c_.values.size()) + " value(s) written and confirmed",
          "\"written\":" + std::to_string(c_.values.size()));
    return kExitOk;
  }

  int watch() {
    std::vector<uint16_t> last;
    for (int n = 0; !stop_ && (c_.polls == 0 || n < c_.polls); ++n) {
      const Result r = link_->execute(readRequest());
      if (!r.ok()) {
        err_ << "read failed: " << r.message << "\n";
      } else if (r.values != last) {
        print(r.values);  // only what changed is worth a line
        last = r.values;
      }
      std::this_thread::sleep_for(std::chrono::duration<double>(c_.interval));
    }
    return last.empty() ? kExitNotFound : kExitOk;
  }

  const CommissionCommand& c_;
  std::istream& in_;
  std::ostream& out_;
  std::ostream& err_;
  const std::atomic<bool>& stop_;
  std::unique_ptr<RtuLink> link_;
};

}  // namespace

int runCommission(const CommissionCommand& command, std::istream& in, std::ostream& out,
                  std::ostream& err, const std::atomic<bool>& stop) {
  return Session(command, in, out, err, stop).run();
}

}  // namespace modbus_rtu_driver
