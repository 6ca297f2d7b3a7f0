#include "modbus_rtu_driver/sim/sim_ld58a08.h"

#include <yaml-cpp/yaml.h>

#include <cmath>

namespace modbus_rtu_driver {

namespace {
constexpr uint16_t kContinuous = 0xFFFF;
const int kBauds[] = {1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200};

double since(SimClock::time_point from, SimClock::time_point now) {
  return std::chrono::duration<double>(now - from).count();
}
}  // namespace

SimLd58a08::SimLd58a08(uint8_t address, SimLineSettings line) : SimDevice(address, line) {
  for (int i = 0; i < 8; ++i)
    if (kBauds[i] == line.baud) baud_code_ = static_cast<uint16_t>(i);
  parity_code_ = line.parity == 'E' ? 1 : line.parity == 'O' ? 2 : 0;
}

void SimLd58a08::start(uint8_t ch, SimClock::time_point now) {
  pwm_[ch].started = now;
  pwm_[ch].started_with = pwm_[ch].reg[2];
}

void SimLd58a08::tick(SimClock::time_point now) {
  for (uint8_t ch = 0; ch < 8; ++ch) {
    Channel& c = pwm_[ch];
    const uint8_t bit = static_cast<uint8_t>(1u << ch);
    if (c.reg[2] == 0) continue;  // PWM off: the output is a plain DO
    const double elapsed = since(c.started, now);
    if (ch >= 6) {  // fast: on while the output time runs (a 20 kHz wave cannot be sampled)
      if (c.started_with != kContinuous) {
        const double left = c.started_with * 0.1 - elapsed;
        if (left <= 0) {
          c.reg[2] = 0;
          outputs_ &= static_cast<uint8_t>(~bit);
          continue;
        }
        c.reg[2] = static_cast<uint16_t>(std::ceil(left * 10.0 - 1e-9));
      }
      outputs_ |= bit;
      continue;
    }
    const double period = c.reg[0] * 0.1, on = c.reg[1] * 0.1;
    if (period <= 0) continue;
    const auto done = static_cast<long>(elapsed / period);
    if (c.started_with != kContinuous) {
      if (done >= c.started_with) {  // the set number of pulses is out: stop
        c.reg[2] = 0;
        outputs_ &= static_cast<uint8_t>(~bit);
        continue;
      }
      c.reg[2] = static_cast<uint16_t>(c.started_with - done);
    }
    const bool high = std::fmod(elapsed, period) < on;
    outputs_ = high ? (outputs_ | bit) : (outputs_ & static_cast<uint8_t>(~bit));
  }
}

uint8_t SimLd58a08::read(Table table, uint16_t a, SimClock::time_point now, uint16_t* v) {
  tick(now);
  if (table == Table::kCoil) {
    if (a > 7) return kIllegalDataAddress;
    *v = (outputs_ >> a) & 1;
    return 0;
  }
  if (table != Table::kHolding) return kIllegalFunction;  // FC02/FC04 are not supported
  if (a < 0x80) {
    if ((a & 0x0F) > 2) return kIllegalDataAddress;
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
    for (size_t i = 0; i < values.size(); ++i) {
      const uint8_t bit = static_cast<uint8_t>(1u << (a + i));
      outputs_ = values[i] ? (outputs_ | bit) : (outputs_ & static_cast<uint8_t>(~bit));
    }
    return 0;
  }
  if (table != Table::kHolding) return kIllegalFunction;
  // Check every address first so a bad one changes nothing.
  for (size_t i = 0; i < values.size(); ++i) {
    const uint32_t r = a + i;
    const bool pwm = r < 0x80 && (r & 0x0F) <= 2;
    if (!pwm && r != 0x80 && (r < 0xFA || r > 0xFF)) return kIllegalDataAddress;
  }
  for (size_t i = 0; i < values.size(); ++i) {
    const uint8_t e = writeHolding(static_cast<uint16_t>(a + i), values[i], now);
    if (e) return e;
  }
  return 0;
}

uint8_t SimLd58a08::writeHolding(uint16_t a, uint16_t v, SimClock::time_point now) {
  if (a < 0x80) {
    const uint8_t ch = static_cast<uint8_t>(a >> 4);
    pwm_[ch].reg[a & 0x0F] = v;
    if ((a & 0x0F) == 2) {
      if (v != 0) {
        start(ch, now);
      } else {
        outputs_ &= static_cast<uint8_t>(~(1u << ch));
      }
    }
    return 0;
  }
  switch (a) {
    case 0x0080:
      outputs_ = static_cast<uint8_t>(v & 0xFF);
      return 0;
    case 0x00FA:
      if (v > 1) return kIllegalDataValue;
      save_ = v;
      return 0;
    case 0x00FB:
      factoryReset();
      return 0;
    case 0x00FC:
      return_delay_ = v > 25 ? 0 : v;
      return 0;  // over 25: back to 0 (manual)
    case 0x00FD:
      if (v < 1 || v > 247) return kIllegalDataValue;
      address_ = static_cast<uint8_t>(v);  // answers at the new address from the next request
      return 0;
    case 0x00FE:
      if (v > 7)
        factoryReset();  // "Others: Factory reset"
      else
        baud_code_ = v;
      return 0;
    case 0x00FF:
      parity_code_ = v;
      return 0;  // >2 becomes 0 at power-on
    default:
      return kIllegalDataAddress;
  }
}

void SimLd58a08::factoryReset() {
  address_ = 1;
  baud_code_ = 3;
  parity_code_ = 0;
  return_delay_ = 0;
  save_ = 0;
  pwm_ = {};
  outputs_ = 0;
}

void SimLd58a08::powerCycle() {
  line_.baud = kBauds[baud_code_ < 8 ? baud_code_ : 3];
  if (parity_code_ > 2) parity_code_ = 0;
  line_.parity = parity_code_ == 1 ? 'E' : parity_code_ == 2 ? 'O' : 'N';
  outputs_ = 0;
  const auto now = SimClock::now();
  for (uint8_t ch = 0; ch < 8; ++ch) {
    if (!save_) {
      pwm_[ch] = Channel{};
    } else if (pwm_[ch].reg[2]) {
      start(ch, now);  // saved parameters run again after power-on
    }
  }
}

void SimLd58a08::saveState(YAML::Node& n) const {
  n["address"] = static_cast<int>(address_);
  n["baud_code"] = baud_code_;
  n["parity_code"] = parity_code_;
  n["baud"] = line_.baud;
  n["parity"] = std::string(1, line_.parity);
  n["return_delay"] = return_delay_;
  n["save"] = save_;
  if (save_)
    for (uint8_t ch = 0; ch < 8; ++ch)
      for (int r = 0; r < 3; ++r) n["pwm"].push_back(pwm_[ch].reg[r]);
}

void SimLd58a08::loadState(const YAML::Node& n) {
  address_ = static_cast<uint8_t>(n["address"].as<int>(address_));
  baud_code_ = n["baud_code"].as<uint16_t>(baud_code_);
  parity_code_ = n["parity_code"].as<uint16_t>(parity_code_);
  line_.baud = n["baud"].as<int>(line_.baud);
  line_.parity = n["parity"].as<std::string>(std::string(1, line_.parity))[0];
  return_delay_ = n["return_delay"].as<uint16_t>(return_delay_);
  save_ = n["save"].as<uint16_t>(save_);
  if (n["pwm"] && n["pwm"].size() == 24) {
    const auto now = SimClock::now();
    for (uint8_t ch = 0; ch < 8; ++ch) {
      for (int r = 0; r < 3; ++r) pwm_[ch].reg[r] = n["pwm"][ch * 3 + r].as<uint16_t>();
      if (pwm_[ch].reg[2]) start(ch, now);
    }
  }
}

}  // namespace modbus_rtu_driver
