// What modbus_rtu_commission does with a board of one type: tell it apart from the others by
// harmless reads, list its settings, and read and change its address, baud rate, parity, return
// delay, power-down save and factory settings. Each type that has any of these implements this
// in its own file (src/devices/<type>_commissioning.cpp) and registers it there:
//   const bool kRegistered = commissioningClasses().add(kMytypeType, &kMytypeCommissioning);
// so the tool (src/tools) names no type: a new type edits nothing there.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "modbus_rtu_driver/core/config/type_registry.h"
#include "modbus_rtu_driver/core/link/transport.h"
#include "modbus_rtu_driver/core/modbus/types.h"
#include "modbus_rtu_driver/devices/device.h"

namespace modbus_rtu_driver {

// What a type can change besides reading its outputs. The tool offers a command for a type
// only when its class says it has the feature.
enum class BoardFeature {
  kAddress,        // get-address, set-address
  kBaud,           // get-baud, set-baud (a code that indexes kStandardBauds)
  kParity,         // get-parity, set-parity (code 0 none, 1 even, 2 odd)
  kReturnDelay,    // get-return-delay, set-return-delay (in steps of returnDelayStepMs())
  kPowerDownSave,  // get-save, set-save (0 off, 1 on)
  kFactoryReset,   // factory-reset
  kLimits,         // get-limits, set-limits: protection limits held in registers
};

// One protection limit (kLimits): its name (an option --over-voltage for "over_voltage"), unit
// and the decimals its register's step has (0.1 V: 1).
struct LimitSpec {
  const char* name;
  const char* unit;
  int decimals;
};

// One identification probe's answer.
struct Probe {
  enum Kind {
    kNo,         // not this type (or nothing to tell)
    kYes,        // this type is at the address
    kElsewhere,  // a board of this type answered for another address (its `also_answers`)
  };
  Kind kind = kNo;
  // A read got neither data nor a refusal (a late reply, noise): the type stays open.
  bool unclear = false;
  std::string note;  // kElsewhere: who answered, "an LD58A08 answered for its address 1"
};

// What `info` prints after the type's name: human lines, and the JSON fields they stand for.
using InfoValue = std::variant<int, double, bool, std::string>;
struct InfoReport {
  std::string human;  // each line starts with "\n  "
  std::vector<std::pair<std::string, InfoValue>> fields;
};

// Addresses below -1 are never passed; `at` = kBlind means "without the board's address":
// through the address every board of the type answers (addressPath()).
inline constexpr int kBlind = -1;

class Commissioning {
 public:
  virtual ~Commissioning() = default;

  // --- identification: harmless reads only (scan, info) ---
  // Probes run in ascending order, each after the address answered a coil read; the first
  // kYes names the type. A type whose probe another type's board could also pass goes after
  // that type.
  virtual int probeOrder() const = 0;
  virtual Probe probe(Transport& link, uint8_t address) const = 0;
  // The settings and readings `info` shows.
  virtual Result report(Transport& link, uint8_t address, InfoReport* out) const = 0;

  virtual bool has(BoardFeature feature) const = 0;
  // The board in a sentence: "the LC relay board".
  virtual std::string title() const = 0;

  // --- address (kAddress) ---
  // How the board is reached without its address, for messages: "through 0xFF".
  virtual std::string addressPath() const { return ""; }
  // False when the board has no address register at its own address (only addressPath()):
  // `get-address --address A` then only checks that it answers at A.
  virtual bool addressReadableAt() const { return true; }
  virtual Result readAddress(Transport& link, int at, uint16_t* address) const;
  virtual Result writeAddress(Transport& link, int at, uint16_t address) const;
  // A harmless read at `address`: success when the board answers there (and, where it can
  // tell, says that is its address); after a change, and for a board whose address cannot be
  // read at its own address.
  virtual Result answersAt(Transport& link, int address) const;
  // The question's warning for a change through addressPath(): who else takes it.
  virtual std::string addressPathWarning() const { return ""; }
  // Said after the question: how the board behaves once changed ("" if nothing to add).
  virtual std::string afterAddressChange() const { return ""; }
  // A hint appended to a failed address read (another type may have answered), or "".
  virtual std::string addressReadHint(const Result& failed, int at) const {
    (void)failed;
    (void)at;
    return "";
  }

  // --- baud rate (kBaud): codes first..second index kStandardBauds ---
  virtual std::pair<int, int> baudCodes() const { return {0, 0}; }
  // Appended to "It takes effect after the device is powered off and on" (" (the manual ...)").
  virtual std::string powerCycleAdvice() const { return ""; }

  // --- return delay (kReturnDelay): units of returnDelayStepMs() up to returnDelayMaxUnits() ---
  virtual int returnDelayStepMs() const { return 0; }
  virtual int returnDelayMaxUnits() const { return 0; }

  // kBaud, kParity, kReturnDelay, kPowerDownSave at `address`, as the register holds them.
  virtual Result readSetting(Transport& link, int address, BoardFeature which,
                             uint16_t* value) const;
  virtual Result writeSetting(Transport& link, int address, BoardFeature which,
                              uint16_t value) const;

  // --- limits (kLimits), as the registers hold them, in limitList()'s order ---
  virtual std::vector<LimitSpec> limitList() const { return {}; }
  // The manual's rules in words, for --help.
  virtual std::string limitRules() const { return ""; }
  // Limit `which` in its unit as the register value that would be written, checked against
  // its own rule there; messages call it `option`. Empty when fine.
  virtual std::string limitToRegister(size_t which, double value, uint16_t* reg,
                                      const std::string& option) const;
  // All the rules, on the register values of every limit; empty when they hold.
  virtual std::string checkLimits(const std::vector<uint16_t>& regs) const;
  virtual Result readLimits(Transport& link, int address, std::vector<uint16_t>* regs) const;
  // Checked first (nothing is sent when a rule is broken), then written and read back: a
  // device that holds other values afterwards is a failure.
  virtual Result writeLimits(Transport& link, int address, const std::vector<uint16_t>& regs) const;

  // --- factory reset (kFactoryReset); the factory settings are the descriptor's ---
  // What else the reset restores, for the question: ", no return delay, PWM settings cleared".
  virtual std::string factoryResetAlsoText() const { return ""; }
  // " (every LD58A08 on the bus)": who takes a reset through addressPath().
  virtual std::string factoryResetPathWarning() const { return ""; }
  virtual Result factoryReset(Transport& link, int at) const;

 protected:
  static Result unsupported();
  // A probe by one harmless read: an answer with data goes to `judge`, which sets the kind (and
  // the note); any other answer only decides whether the type stays open (unclear).
  static Probe probeByRead(
      Transport& link, const Request& read,
      const std::function<void(const std::vector<uint16_t>& values, Probe* probe)>& judge);
};

// Registered per type from the type's own file; the registry holds a pointer to a static
// instance of the class.
using CommissioningClass = const Commissioning*;
TypeRegistry<CommissioningClass>& commissioningClasses();

// 1200 ... 115200 for codes 0-7 (kStandardBauds), 0 for another code.
int baudOfCode(int code);
// "9600 baud (code 3)", or "code 9 (not a baud rate)".
std::string baudCodeText(int code);
// "none", "even", "odd" for the parity codes 0-2, else "code N".
std::string parityCodeText(int code);
// A gateway's own exceptions (tcp://, the node's share): 0A "path unavailable" (its line is not
// open) and 0B "target device failed to respond". They say nobody answered behind it.
inline bool gatewayHeardNothing(const Result& r) {
  return r.error == ErrorKind::kException &&
         (r.exception_code == kGatewayPathUnavailable || r.exception_code == kGatewayTargetFailed);
}
// An answer, even an exception, means something listens there; a gateway's 0A / 0B does not
// (they come from the gateway, not from a device). Garbage does not either: at a wrong baud,
// noise and half frames are what a scan hears most.
inline bool answered(const Result& r) {
  return r.ok() || (r.error == ErrorKind::kException && !gatewayHeardNothing(r));
}

// The settings of a board of `type` at `address`, named after its type, as the classes build
// the type's device to ask it.
DeviceConfig boardConfig(const DeviceDescriptor& type, int address);

// A registered type's class with its descriptor.
struct CommissioningType {
  const DeviceDescriptor* type;
  const Commissioning* commissioning;
};
// Every registered type, in probe order (then by name).
std::vector<CommissioningType> commissioningTypes();
// The registered class of `name`, or null.
const Commissioning* commissioningOf(const std::string& name);

}  // namespace modbus_rtu_driver
