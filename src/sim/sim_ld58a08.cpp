#include "modbus_rtu_driver/sim/sim_ld58a08.h"

#include <yaml-cpp/yaml.h>

#include "modbus_rtu_driver/sim/simulator.h"

namespace modbus_rtu_driver {

// `type: ld58a08` in the simulator's file builds this class (sim/simulator.h).
[[maybe_unused]] const bool kSimLd58a08Registered =
    simDeviceClasses().add(kLd58a08Type, makeSimDeviceOf<SimLd58a08>);

namespace {

constexpr uint16_t kContinuous = 0xFFFF;
constexpr int64_t kTenth = 100'000'000;  // 0.1 s in ns: the unit of periods and output times
// Baud codes 0-7: the standard rates in order (its manual).
const auto& kBauds = kStandardBauds;

bool isPwmRegister(uint32_t r) {
  return r < 0x80 && (r & 0x0F) <= 2;
}
bool isSpecialRegister(uint32_t r) {
  return r == 0x0080 || (r >= 0x00FA && r <= 0x00FF);
}
// The manual's parity codes 0 none, 1 even, 2 odd are Parity's order (enum class Parity).
Parity parityOfCode(uint16_t code) {
  return code <= 2 ? static_cast<Parity>(code) : Parity::kNone;
}

}  // namespace

SimLd58a08::SimLd58a08(uint8_t address, SimLineSettings line) : SimDevice(address, line) {
  for (uint16_t i = 0; i < 8; ++i)
    if (kBauds[i] == line.baud) baud_code_ = i;
  parity_code_ = static_cast<uint16_t>(line.parity);
}

void SimLd58a08::setOutput(uint8_t ch, bool on) {
  const uint8_t bit = static_cast<uint8_t>(1u << ch);
  outputs_ = on ? (outputs_ | bit) : (outputs_ & static_cast<uint8_t>(~bit));
}

void SimLd58a08::anchor(uint8_t ch, SimClock::time_point now) {
  pwm_[ch].anchor = now;
  pwm_[ch].anchored_with = pwm_[ch].reg[2];
}

void SimLd58a08::stopChannel(uint8_t ch) {
  pwm_[ch].reg[2] = 0;
  setOutput(ch, false);
}

// Pulses and output times follow from the time since the anchor, so the result does not
// depend on how often tick() runs.
void SimLd58a08::tick(SimClock::time_point now) {
  for (uint8_t ch = 0; ch < 8; ++ch) {
    Channel& c = pwm_[ch];
    if (c.reg[2] == 0) continue;  // PWM off: the output is a plain DO
    const int64_t elapsed =
        std::chrono::duration_cast<std::chrono::nanoseconds>(now - c.anchor).count();
    if (ch >= 6) {  // fast: on while the output time runs (a 10 kHz wave cannot be sampled)
      if (c.anchored_with != kContinuous) {
        const int64_t left = c.anchored_with * kTenth - elapsed;
        if (left <= 0) {
          stopChannel(ch);
          continue;
        }
        c.reg[2] = static_cast<uint16_t>((left + kTenth - 1) / kTenth);  // counts down
      }
      setOutput(ch, c.reg[1] > 0);
      continue;
    }
    const int64_t period = c.reg[0] * kTenth;
    if (period <= 0) {  // only a hand-edited state file gets here
      stopChannel(ch);
      continue;
    }
    const int64_t done = elapsed / period;
    if (c.anchored_with != kContinuous) {
      if (done >= c.anchored_with) {  // the set number of pulses is out: stop
        stopChannel(ch);
        continue;
      }
      c.reg[2] = static_cast<uint16_t>(c.anchored_with - done);
    }
    setOutput(ch, elapsed % period < c.reg[1] * kTenth);
  }
}

bool SimLd58a08::startsSomething(const Request& r) const {
  if (isBitFunction(r.function)) return false;
  for (size_t i = 0; i < r.values.size(); ++i) {
    const uint32_t a = r.address + i;
    if (a <= 0xFFFF && isPwmRegister(static_cast<uint16_t>(a)) && (a & 0x0F) == 2 &&
        r.values[i] != 0)
      return true;
  }
  return false;
}

uint8_t SimLd58a08::read(Table table, uint16_t a, SimClock::time_point now, uint16_t* v) {
  tick(now);
  if (table == Table::kCoil) {
    if (a > 7) return kIllegalDataAddress;
    *v = (outputs_ >> a) & 1;
    return 0;
  }
  if (table != Table::kHoldingRegister) return kIllegalFunction;  // FC02/FC04 are not supported
  if (isPwmRegister(a)) {
    *v = pwm_[a >> 4].reg[a & 0x0F];
    return 0;
  }
  switch (a) {
    case 0x0080:
      *v = outputs_;
      return 0;
    case 0x00FA:
      *v = save_;
      return 0;
    case 0x00FB:
      *v = 0;
      return 0;
    case 0x00FC:
      *v = return_delay_;
      return 0;
    case 0x00FD:
      *v = address_;
      return 0;
    case 0x00FE:
      *v = baud_code_;
      return 0;
    case 0x00FF:
      *v = parity_code_;
      return 0;
    default:
      return kIllegalDataAddress;
  }
}

uint8_t SimLd58a08::write(Table table, uint16_t a, const std::vector<uint16_t>& values,
                          SimClock::time_point now) {
  tick(now);
  if (table == Table::kCoil) {
    if (a + values.size() > 8) return kIllegalDataAddress;
    for (size_t i = 0; i < values.size(); ++i)
      setOutput(static_cast<uint8_t>(a + i), values[i] != 0);
    tick(now);  // a running PWM keeps its output
    return 0;
  }
  if (table != Table::kHoldingRegister) return kIllegalFunction;
  const uint8_t e = checkHolding(a, values);
  if (e) return e;
  for (size_t i = 0; i < values.size(); ++i)
    writeHolding(static_cast<uint16_t>(a + i), values[i], now);
  tick(now);
  return 0;
}

// The whole write against the state it would leave: unknown addresses (02) first, then values.
uint8_t SimLd58a08::checkHolding(uint16_t a, const std::vector<uint16_t>& values) const {
  for (size_t i = 0; i < values.size(); ++i)
    if (!isPwmRegister(a + i) && !isSpecialRegister(a + i)) return kIllegalDataAddress;
  std::array<Registers, 8> next;
  std::array<uint8_t, 8> touched{};  // bit n: register n of the channel written
  for (uint8_t ch = 0; ch < 8; ++ch) next[ch] = pwm_[ch].reg;
  for (size_t i = 0; i < values.size(); ++i) {
    const uint32_t r = a + i;
    const uint16_t v = values[i];
    if (isPwmRegister(r)) {
      const uint8_t ch = static_cast<uint8_t>(r >> 4), sub = static_cast<uint8_t>(r & 0x0F);
      next[ch][sub] = v;
      touched[ch] = static_cast<uint8_t>(touched[ch] | (1u << sub));
      const bool fast = ch >= 6;
      if (sub == 0 && (v == 0 || (fast && v > 20000))) return kIllegalDataValue;
      if (sub == 1 && (fast ? v > 100 : v == 0xFFFF)) return kIllegalDataValue;
    } else if ((r == 0x0080 && v > 0xFF) || (r == 0x00FA && v > 1) ||
               (r == 0x00FD && (v < 1 || v > 248))) {
      return kIllegalDataValue;
    }
  }
  for (uint8_t ch = 0; ch < 8; ++ch) {
    if (!touched[ch]) continue;
    const Registers& n = next[ch];
    const bool running = n[2] != 0;
    if (running && n[0] == 0) return kIllegalDataValue;  // no period / frequency to run at
    // On-time longer than the period: refused when the channel runs or both come together.
    if (ch < 6 && n[1] > n[0] && (running || (touched[ch] & 0x3) == 0x3)) return kIllegalDataValue;
  }
  return 0;
}

void SimLd58a08::writeHolding(uint16_t a, uint16_t v, SimClock::time_point now) {
  if (isPwmRegister(a)) {
    const uint8_t ch = static_cast<uint8_t>(a >> 4), sub = static_cast<uint8_t>(a & 0x0F);
    Channel& c = pwm_[ch];
    const bool was_running = c.reg[2] != 0;
    c.reg[sub] = v;
    c.stored[sub] = v;
    if (sub == 2 && v == 0) {
      if (was_running) stopChannel(ch);
    } else if (sub == 2 || was_running) {
      anchor(ch, now);  // (re)start; new timing restarts the current pulse with what is left
    }
    return;
  }
  switch (a) {
    case 0x0080:
      for (uint8_t ch = 0; ch < 8; ++ch) setOutput(ch, (v >> ch) & 1);
      return;
    case 0x00FA:
      save_ = v;
      return;
    case 0x00FB:
      factoryReset();
      return;
    case 0x00FC:
      return_delay_ = v > 25 ? 0 : v;  // over 25: back to 0 (manual)
      return;
    case 0x00FD:
      address_ = static_cast<uint8_t>(v);  // answers at the new address from the next request
      return;
    case 0x00FE:
      if (v > 7)
        factoryReset();  // "8: Factory reset", "Others: Factory reset"
      else
        baud_code_ = v;
      return;
    case 0x00FF:
      parity_code_ = v;  // > 2 becomes 0 at power-on (manual)
      return;
    default:
      return;
  }
}

void SimLd58a08::factoryReset() {
  address_ = 1;
  baud_code_ = 3;
  parity_code_ = 0;
  return_delay_ = 0;
  save_ = 0;
  for (uint8_t ch = 0; ch < 8; ++ch) {
    if (pwm_[ch].reg[2]) stopChannel(ch);
    pwm_[ch] = Channel{};
  }
}

void SimLd58a08::restartSaved(SimClock::time_point now) {
  for (uint8_t ch = 0; ch < 8; ++ch) {
    pwm_[ch].reg = pwm_[ch].stored;
    if (pwm_[ch].reg[2]) anchor(ch, now);  // saved parameters run again after power-on
  }
}

void SimLd58a08::powerCycle(SimClock::time_point now) {
  if (parity_code_ > 2) parity_code_ = 0;
  line_.baud = kBauds[baud_code_ < 8 ? baud_code_ : 3];
  line_.parity = parityOfCode(parity_code_);
  outputs_ = 0;
  if (save_) {
    restartSaved(now);
  } else {
    pwm_ = {};
  }
  tick(now);
}

void SimLd58a08::saveState(YAML::Node& n) const {
  n["address"] = static_cast<int>(address_);
  n["baud_code"] = baud_code_;
  n["parity_code"] = parity_code_;
  n["baud"] = line_.baud;
  n["parity"] = parityName(line_.parity);
  n["return_delay"] = return_delay_;
  n["save"] = save_;
  if (save_)
    for (const Channel& c : pwm_)
      for (uint16_t r : c.stored) n["pwm"].push_back(r);
}

void SimLd58a08::loadState(const YAML::Node& n, SimClock::time_point now) {
  const int address = n["address"].as<int>(address_);
  if (address >= 1 && address <= 248) address_ = static_cast<uint8_t>(address);
  baud_code_ = n["baud_code"].as<uint16_t>(baud_code_);
  parity_code_ = n["parity_code"].as<uint16_t>(parity_code_);
  line_.baud = n["baud"].as<int>(line_.baud);
  line_.parity = parseParity(n["parity"].as<std::string>(""), nullptr).value_or(line_.parity);
  return_delay_ = n["return_delay"].as<uint16_t>(return_delay_);
  save_ = n["save"].as<uint16_t>(save_) ? 1 : 0;
  if (save_ && n["pwm"] && n["pwm"].IsSequence() && n["pwm"].size() == 24) {
    for (size_t ch = 0; ch < 8; ++ch)
      for (size_t r = 0; r < 3; ++r) pwm_[ch].stored[r] = n["pwm"][ch * 3 + r].as<uint16_t>(0);
    restartSaved(now);
  }
}

}  // namespace modbus_rtu_driver
