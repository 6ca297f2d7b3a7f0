// The DM500 master's `garbage` step: a stream of random and malformed traffic at the slave,
// with a valid read after each piece that must still get its true answer. Nothing written:
// the junk never holds a valid write for the slave, so the probed value cannot change.
#include <unistd.h>

#include <chrono>
#include <random>
#include <thread>

#include "modbus_rtu_driver/sim/dm500_master.h"

namespace modbus_rtu_driver {

namespace {

Bytes junk(std::mt19937& random, uint8_t id) {
  auto byte = [&] { return static_cast<uint8_t>(random() & 0xFF); };
  Bytes out;
  switch (random() % 5) {
    case 0:  // line noise
      for (unsigned n = 1 + random() % 40; n; --n) out.push_back(byte());
      return out;
    case 1:  // a frame for us with a bad CRC
      out = encodeRequest(Request::writeSingleRegister(id, byte(), byte()));
      out.back() ^= 0x5A;
      return out;
    case 2: {  // an unknown function with some data
      static const uint8_t kUnknown[] = {0x07, 0x08, 0x11, 0x14, 0x17, 0x2B, 0x41, 0x64};
      out = {id, kUnknown[random() % sizeof kUnknown]};
      for (unsigned n = random() % 6; n; --n) out.push_back(byte());
      appendCrc(out);
      return out;
    }
    case 3: {  // a read anywhere, any count: answers or exceptions 02 / 03
      const auto fc = static_cast<FunctionCode>(1 + random() % 4);
      Request r;
      r.slave = id;
      r.function = fc;
      r.address = static_cast<uint16_t>(random() % 100);
      r.count = static_cast<uint16_t>(random() % 300);
      out = {id,
             static_cast<uint8_t>(fc),
             static_cast<uint8_t>(r.address >> 8),
             static_cast<uint8_t>(r.address),
             static_cast<uint8_t>(r.count >> 8),
             static_cast<uint8_t>(r.count)};
      appendCrc(out);
      return out;
    }
    default: {  // any valid-looking frame for another slave
      const uint8_t other = static_cast<uint8_t>(1 + random() % 247);
      out = {other == id ? static_cast<uint8_t>(id % 247 + 1) : other, byte()};
      for (unsigned n = random() % 12; n; --n) out.push_back(byte());
      appendCrc(out);
      return out;
    }
  }
}

}  // namespace

bool Dm500Master::garbage(uint8_t id, long rounds, unsigned seed, uint16_t address, uint16_t value,
                          std::string* why) {
  std::mt19937 random(seed);
  const Request probe = Request::readHoldingRegisters(id, address, 1);
  for (long i = 0; i < rounds; ++i) {
    const Bytes bytes = junk(random, id);
    if (write(pty_.fd(), bytes.data(), bytes.size()) < 0) {
      *why = "cannot write to the pty";
      return false;
    }
    // Let the slave see the line fall silent and answer what it may (drained by transact).
    std::this_thread::sleep_for(std::chrono::milliseconds(15));
    const Result r = transact(probe);
    if (!r.ok() || r.values.size() != 1 || r.values[0] != value) {
      *why = "round " + std::to_string(i) + " after " + toHex(bytes) + ": " +
             (r.ok() ? "read " + std::to_string(r.values.empty() ? -1 : r.values[0]) : r.message);
      return false;
    }
  }
  return true;
}

}  // namespace modbus_rtu_driver
