#include "modbus_rtu_driver/sim/dm500_master.h"

#include <poll.h>
#include <unistd.h>

#include <chrono>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include "modbus_rtu_driver/core/modbus/text.h"

namespace modbus_rtu_driver {

namespace {

using Steady = std::chrono::steady_clock;

std::vector<std::string> words(const std::string& line) {
  std::istringstream in(line.substr(0, line.find('#')));
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

// The `garbage` step: a stream of random and malformed traffic at the slave, with a valid read
// after each piece that must still get its true answer. Nothing written: the junk never holds a
// valid write for the slave, so the probed value cannot change.
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

Bytes Dm500Master::readFor(double seconds, size_t max_bytes, const Request* request) {
  Bytes in;
  const auto deadline = Steady::now() + std::chrono::duration<double>(seconds);
  while (Steady::now() < deadline && in.size() < max_bytes) {
    if (request) {
      const size_t need = replyLengthFromHeader(*request, in);
      if (need && in.size() >= need) break;
    }
    pollfd p{pty_.fd(), POLLIN, 0};
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Steady::now());
    if (poll(&p, 1, static_cast<int>(std::max<long>(1, left.count()))) <= 0) continue;
    uint8_t buf[256];
    const ssize_t n = read(pty_.fd(), buf, sizeof buf);
    if (n > 0) in.insert(in.end(), buf, buf + n);
  }
  return in;
}

Result Dm500Master::transact(const Request& request) {
  // Drop anything stale (e.g. the answer to a raw frame) so it is not read as this reply.
  for (pollfd p{pty_.fd(), POLLIN, 0}; poll(&p, 1, 0) > 0;) {
    uint8_t buf[256];
    if (read(pty_.fd(), buf, sizeof buf) <= 0) break;
  }
  Result refused;
  const std::optional<EncodedRequest> encoded = EncodedRequest::encode(request, &refused);
  if (!encoded) return refused;
  const Bytes& frame = encoded->adu();
  if (write(pty_.fd(), frame.data(), frame.size()) != static_cast<ssize_t>(frame.size()))
    return Result::failure(ErrorKind::kIo, "cannot write to the pty");
  if (!request.expectsReply()) {  // a broadcast: nobody may answer
    const Bytes got = readFor(0.2, 256, nullptr);
    if (!got.empty())
      return Result::failure(ErrorKind::kMalformed, "a broadcast was answered: " + toHex(got));
    return Result::success(request.values);
  }
  const Bytes reply = readFor(timeout_, 256, &request);
  if (reply.empty()) return Result::failure(ErrorKind::kTimeout, request.describe() + ": no reply");
  return decodeReply(*encoded, reply);
}

bool Dm500Master::step(const std::string& line, std::string* why) {
  const auto w = words(line);
  if (w.empty()) return true;
  const std::string& op = w[0];
  auto num = [&](size_t i) -> long {
    if (i >= w.size()) throw std::runtime_error("missing argument " + std::to_string(i));
    return std::stol(w[i], nullptr, 0);
  };
  try {
    if (op == "sleep") {
      std::this_thread::sleep_for(std::chrono::duration<double>(std::stod(w.at(1))));
      return true;
    }
    if (op == "raw") {
      Bytes bytes;
      for (size_t i = 1; i < w.size(); ++i)
        bytes.push_back(static_cast<uint8_t>(std::stoul(w[i], nullptr, 16)));
      if (write(pty_.fd(), bytes.data(), bytes.size()) < 0)
        throw std::runtime_error("write failed");
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      return true;
    }
    if (op == "garbage")
      return garbage(static_cast<uint8_t>(num(1)), num(2), static_cast<unsigned>(num(3)),
                     static_cast<uint16_t>(num(4)), static_cast<uint16_t>(num(5)), why);
    // Tail keywords: expect / equals V..., exception CODE, silence, within S.
    size_t tail = w.size();
    for (size_t i = 1; i < w.size(); ++i)
      if (w[i] == "expect" || w[i] == "equals" || w[i] == "exception" || w[i] == "silence" ||
          w[i] == "within") {
        tail = i;
        break;
      }
    std::vector<uint16_t> expected;
    int exception = 0;
    bool silence = false, check_values = false;
    double within = 0;
    for (size_t i = tail; i < w.size(); ++i) {
      if (w[i] == "expect" || w[i] == "equals")
        check_values = true;
      else if (w[i] == "exception")
        exception = static_cast<int>(num(++i));
      else if (w[i] == "silence")
        silence = true;
      else if (w[i] == "within")
        within = std::stod(w.at(++i));
      else
        expected.push_back(static_cast<uint16_t>(num(i)));
    }
    const auto id = static_cast<uint8_t>(num(1));
    Request req;
    if (op == "wait_ready") {
      req = Request::readHoldingRegisters(id, 0, 1);
    } else {
      const auto addr = static_cast<uint16_t>(num(2));
      if (op == "write_coils") {
        const auto count = static_cast<uint16_t>(num(3));
        std::vector<bool> bits;
        for (uint16_t i = 0; i < count; ++i) {
          const size_t byte = 4 + i / 8;
          const auto b = static_cast<uint8_t>(std::stoul(w.at(byte), nullptr, 16));
          bits.push_back((b >> (i % 8)) & 1);
        }
        req = Request::writeMultipleCoils(id, addr, bits);
      } else if (op == "write_bytes") {
        std::vector<uint16_t> regs;
        for (size_t i = 3; i < tail; i += 2) {
          const long lo = num(i), hi = i + 1 < tail ? num(i + 1) : 0;
          regs.push_back(static_cast<uint16_t>(hi << 8 | lo));
        }
        req = Request::writeMultipleRegisters(id, addr, regs);
      } else if (op == "write_coil") {
        req = Request::writeSingleCoil(id, addr, num(3) != 0);
      } else if (op == "write_register") {
        req = Request::writeSingleRegister(id, addr, static_cast<uint16_t>(num(3)));
      } else {
        const auto count = static_cast<uint16_t>(num(3));
        // read_<table> and wait_<table>, the table by its one name (read_holding_register).
        const auto verb = op.substr(0, op.find('_'));
        std::string problem;
        const auto table = parseTableName(op.substr(op.find('_') + 1), &problem);
        if ((verb != "read" && verb != "wait") || !table)
          throw std::runtime_error("unknown step '" + op + "'" +
                                   (verb == "read" || verb == "wait" ? ": " + problem : ""));
        req = Request::read(id, *table, addr, count);
      }
    }
    const bool waiting = op.rfind("wait_", 0) == 0;
    const auto deadline = Steady::now() + std::chrono::duration<double>(within);
    for (;;) {
      const Result r = transact(req);
      std::string problem;
      if (silence) {
        const bool quiet = req.expectsReply() ? r.error == ErrorKind::kTimeout : r.ok();
        if (!quiet) problem = "expected silence, got an answer";
      } else if (exception) {
        if (r.exception_code != exception)
          problem = "expected exception " + std::to_string(exception) +
                    ", got: " + (r.ok() ? "a normal reply" : r.message);
      } else if (!r.ok()) {
        problem = r.message;
      } else if (check_values && r.values != expected) {
        problem = "read " + join(r.values, " ") + ", expected " + join(expected, " ");
      }
      if (problem.empty()) return true;
      if (!waiting || Steady::now() >= deadline) {
        *why = problem;
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  } catch (const std::exception& e) {
    *why = std::string("bad step: ") + e.what();
    return false;
  }
}

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
