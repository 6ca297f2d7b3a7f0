// libFuzzer target: arbitrary bytes at the slave role's request handling (our framer, then
// libmodbus's modbus_reply on the real mapping), replies written to a real pty. Invariants:
// nothing crashes (ASan/UBSan watch), every byte the server sends forms valid frames, and a
// valid request after the garbage is still answered correctly.
#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <cstdlib>
#include <memory>

#include "modbus_rtu_driver/core/modbus/frame.h"
#include "modbus_rtu_driver/core/server/slave_server.h"

using namespace modbus_rtu_driver;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

struct Bench {
  int master = -1;
  std::unique_ptr<SlaveServer> server;

  Bench() {
    master = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
    check(master >= 0 && grantpt(master) == 0 && unlockpt(master) == 0);
    SlaveConfig config;
    config.link.port = ptsname(master);
    config.link.baud = 115200;
    config.slave_id = 7;
    config.coils = config.discrete_inputs = config.holding_registers = config.input_registers = 32;
    server = std::make_unique<SlaveServer>(config, [](const SlaveWrite& w) {
      check(w.values.size() >= 1 && w.address < 32);  // only writes the mapping allowed
    });
    std::string error;
    check(server->openPort(&error));
  }
  // Everything the server wrote since the last call.
  Bytes drain() {
    Bytes out;
    uint8_t buf[4096];
    for (ssize_t n; (n = read(master, buf, sizeof buf)) > 0;) out.insert(out.end(), buf, buf + n);
    return out;
  }
};

// The server's output is whole reply frames back to back, each with a valid CRC, from id 7.
void checkReplies(const Bytes& out) {
  size_t at = 0;
  while (at < out.size()) {
    check(out.size() - at >= 5 && out[at] == 7);
    const uint8_t function = out[at + 1];
    size_t length = 0;
    if (function & 0x80)
      length = 5;
    else if (function <= 4)
      length = 5u + (at + 2 < out.size() ? out[at + 2] : 0);
    else
      length = 8;  // 05, 06, 15, 16 echo 6 bytes + CRC
    check(at + length <= out.size());
    check(hasValidCrc(Bytes(out.begin() + at, out.begin() + at + length)));
    at += length;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Bench bench;
  bench.server->handleInput(data, size, true);
  checkReplies(bench.drain());
  // A valid request afterwards is answered as libmodbus would: holding register 3.
  const Bytes probe = encodeRequest(Request::readHoldingRegisters(7, 3, 1));
  bench.server->handleInput(probe.data(), probe.size(), true);
  const Bytes reply = bench.drain();
  check(reply.size() == 7 && hasValidCrc(reply) && reply[0] == 7 && reply[1] == 3);
  return 0;
}
